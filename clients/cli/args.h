// Command-line arguments shared by the isomesh subcommands: `--name value` options (repeatable ones
// such as `--param a=1.5`), positional arguments, and the number lists options carry (`--at
// 1,2,3`).
#pragma once

#include <map>
#include <optional>
#include <span>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

namespace isomesh::cli {

/// A mistake in the command line. main() prints it with a pointer to `--help` and exits with 2.
class UsageError : public std::runtime_error {
  public:
    using std::runtime_error::runtime_error;
};

struct OptionSpec {
    std::string_view name;  // without the leading "--"
    bool takes_value = true;
    bool repeatable = false;
};

class Arguments {
  public:
    /// Splits `args` into options and positional arguments. An argument starting with "--" is an
    /// option, `--name value` or `--name=value`; anything else is positional, including
    /// expressions such as `-x^2`; a lone "--" makes the rest positional. `--help` is always
    /// accepted. Throws UsageError for an unknown option, a missing value, or a non-repeatable
    /// option given twice. The views point into `args`, which must outlive this object.
    Arguments(std::span<const std::string_view> args, std::span<const OptionSpec> options);

    const std::vector<std::string_view>& positional() const { return positional_; }
    bool has(std::string_view name) const { return options_.contains(name); }
    bool help() const { return has("help"); }
    /// The value of a non-repeatable option, if given.
    std::optional<std::string_view> value(std::string_view name) const;
    /// Every value of a repeatable option, in command-line order.
    std::vector<std::string_view> values(std::string_view name) const;

  private:
    std::vector<std::string_view> positional_;
    std::map<std::string_view, std::vector<std::string_view>, std::less<>> options_;
};

/// A finite decimal number (`1.5`, `-2`, `+1e-3`); throws UsageError naming `what` otherwise.
double parse_number(std::string_view text, std::string_view what);

/// Exactly `count` comma-separated numbers (`1,2,3`); throws UsageError naming `what` otherwise.
std::vector<double> parse_numbers(std::string_view text, std::size_t count, std::string_view what);

/// `name=value` items into a map; throws UsageError for a missing `=`, an empty name, a bad
/// number or a name given twice.
std::map<std::string, double, std::less<>> parse_assignments(
    std::span<const std::string_view> items, std::string_view what);

}  // namespace isomesh::cli
