// Binding parameter values to a compiled tape: a tape names its parameters (Tape::params, in
// first-use order); a request supplies values by name. Compile once, bind again for every new
// slider value.
#pragma once

#include <map>
#include <optional>
#include <string>
#include <vector>

#include "tape/tape.h"

namespace isomesh {

struct ParameterBinding {
    /// values[i] is the value of tape.params[i]; complete only when there is no error.
    std::vector<double> values;
    /// Set when some parameter has no value or a non-finite one: "no value for parameters 'a',
    /// 'b'" lists every one of them.
    std::optional<std::string> error;
    /// Set when names were supplied that the tape does not use ("unused parameter 'c'"). Not an
    /// error: a slider may outlive the term that used it. Callers decide whether to show it.
    std::optional<std::string> warning;
    std::vector<std::string> missing;  // the parameters without a value, in tape order
    std::vector<std::string> unused;   // the supplied names the tape does not use, sorted
    bool ok() const { return !error; }
};

ParameterBinding bind_parameters(const Tape& tape,
                                 const std::map<std::string, double, std::less<>>& values);

}  // namespace isomesh
