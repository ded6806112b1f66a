#include "args.h"

#include <algorithm>
#include <charconv>
#include <cmath>

namespace isomesh::cli {

namespace {

const OptionSpec* find_option(std::span<const OptionSpec> options, std::string_view name) {
    auto it = std::find_if(options.begin(), options.end(),
                           [&](const OptionSpec& o) { return o.name == name; });
    return it == options.end() ? nullptr : &*it;
}

std::string quoted(std::string_view text) {
    return "'" + std::string(text) + "'";
}

}  // namespace

Arguments::Arguments(std::span<const std::string_view> args, std::span<const OptionSpec> options) {
    static constexpr OptionSpec kHelp{"help", false, false};
    for (std::size_t i = 0; i < args.size(); ++i) {
        std::string_view arg = args[i];
        if (arg == "--") {
            positional_.insert(positional_.end(), args.begin() + static_cast<long>(i) + 1,
                               args.end());
            break;
        }
        if (!arg.starts_with("--")) {
            positional_.push_back(arg);
            continue;
        }
        std::string_view name = arg.substr(2, arg.find('=') - 2);
        const OptionSpec* spec = name == "help" ? &kHelp : find_option(options, name);
        if (!spec) throw UsageError("unknown option " + quoted(arg));
        std::optional<std::string_view> inline_value;
        if (arg.find('=') != std::string_view::npos) inline_value = arg.substr(arg.find('=') + 1);
        if (!spec->takes_value && inline_value)
            throw UsageError("option --" + std::string(name) + " takes no value");
        if (spec->takes_value && !inline_value && i + 1 == args.size())
            throw UsageError("option --" + std::string(name) + " needs a value");
        std::vector<std::string_view>& values = options_[name];
        if (!values.empty() && !spec->repeatable)
            throw UsageError("option --" + std::string(name) + " given twice");
        if (spec->takes_value) values.push_back(inline_value ? *inline_value : args[++i]);
        if (!spec->takes_value) values.push_back({});
    }
}

std::optional<std::string_view> Arguments::value(std::string_view name) const {
    auto it = options_.find(name);
    if (it == options_.end()) return std::nullopt;
    return it->second.front();
}

std::vector<std::string_view> Arguments::values(std::string_view name) const {
    auto it = options_.find(name);
    return it == options_.end() ? std::vector<std::string_view>{} : it->second;
}

double parse_number(std::string_view text, std::string_view what) {
    std::string_view digits = text.starts_with('+') ? text.substr(1) : text;
    double value = 0.0;
    auto [end, status] = std::from_chars(digits.data(), digits.data() + digits.size(), value);
    if (digits.empty() || status != std::errc{} || end != digits.data() + digits.size() ||
        !std::isfinite(value))
        throw UsageError(std::string(what) + ": " + quoted(text) + " is not a finite number");
    return value;
}

std::vector<double> parse_numbers(std::string_view text, std::size_t count, std::string_view what) {
    std::vector<double> numbers;
    for (std::size_t start = 0; start <= text.size();) {
        std::size_t comma = std::min(text.find(',', start), text.size());
        numbers.push_back(parse_number(text.substr(start, comma - start), what));
        start = comma + 1;
    }
    if (numbers.size() != count)
        throw UsageError(std::string(what) + " needs " + std::to_string(count) +
                         " comma-separated numbers, got " + std::to_string(numbers.size()));
    return numbers;
}

std::map<std::string, double, std::less<>> parse_assignments(
    std::span<const std::string_view> items, std::string_view what) {
    std::map<std::string, double, std::less<>> result;
    for (std::string_view item : items) {
        std::size_t equals = item.find('=');
        if (equals == std::string_view::npos || equals == 0)
            throw UsageError(std::string(what) + ": expected name=value, got " + quoted(item));
        std::string name(item.substr(0, equals));
        double value = parse_number(item.substr(equals + 1), std::string(what) + " " + name);
        if (!result.emplace(name, value).second)
            throw UsageError(std::string(what) + ": " + quoted(name) + " given twice");
    }
    return result;
}

}  // namespace isomesh::cli
