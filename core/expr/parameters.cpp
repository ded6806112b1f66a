#include "expr/parameters.h"

#include <algorithm>
#include <cmath>

#include "expr/utf8.h"

namespace isomesh {

namespace {

/// "parameter 'a'" or "parameters 'a', 'b'".
std::string list_names(const std::vector<std::string>& names) {
    std::string text = names.size() == 1 ? "parameter " : "parameters ";
    for (std::size_t i = 0; i < names.size(); ++i)
        text += (i == 0 ? "" : ", ") + expr::quote(names[i]);
    return text;
}

}  // namespace

ParameterBinding bind_parameters(const Tape& tape,
                                 const std::map<std::string, double, std::less<>>& values) {
    ParameterBinding binding;
    std::vector<std::string> not_finite;
    for (const std::string& name : tape.params) {
        auto it = values.find(name);
        if (it == values.end()) {
            binding.missing.push_back(name);
        } else if (!std::isfinite(it->second)) {
            not_finite.push_back(name);
        }
        binding.values.push_back(it == values.end() ? 0.0 : it->second);
    }
    for (const auto& [name, value] : values) {
        if (std::find(tape.params.begin(), tape.params.end(), name) == tape.params.end())
            binding.unused.push_back(name);
    }
    std::string error;
    if (!binding.missing.empty()) error = "no value for " + list_names(binding.missing);
    if (!not_finite.empty())
        error += (error.empty() ? "" : "; ") + std::string("non-finite value for ") +
                 list_names(not_finite);
    if (!error.empty()) binding.error = error;
    if (!binding.unused.empty()) binding.warning = "unused " + list_names(binding.unused);
    return binding;
}

}  // namespace isomesh
