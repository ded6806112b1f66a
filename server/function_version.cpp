#include "server/function_version.h"

#include <algorithm>
#include <stdexcept>

#include "eval/tape_field.h"
#include "expr/parameters.h"
#include "expr/vm_reader.h"

namespace isomesh::server {
namespace {

using protocol::ErrorCode;
using protocol::ErrorReply;

ErrorReply reject(const std::optional<protocol::RequestId>& id, ErrorCode code, std::string message,
                  std::optional<std::uint32_t> column = std::nullopt) {
    ErrorReply reply;
    reply.id = id;
    reply.code = code;
    reply.message = std::move(message);
    reply.column = column;
    return reply;
}

/// Compiles the source into version.tape (and state.expression), or says why it cannot.
std::optional<ErrorReply> compile(FunctionVersion& version, const VersionLimits& limits) {
    const protocol::Source& source = version.source;
    CompileResult result = source.kind == protocol::Source::Kind::vm
                               ? read_vm(source.text, limits.compile)
                               : compile_expression(source.text, limits.compile);
    if (!result.ok()) {
        const CompileError& error = *result.error;
        std::optional<std::uint32_t> column;
        if (error.column > 0) column = static_cast<std::uint32_t>(error.column);
        return reject(version.request_id, ErrorCode::bad_expression, error.to_string(), column);
    }
    version.tape = std::make_shared<const Tape>(std::move(result.tape));
    version.state.expression.reset();
    if (source.kind == protocol::Source::Kind::expression) version.state.expression = source.text;
    return std::nullopt;
}

/// A name in `supplied` (this request's parameters) that the function does not use and the
/// session never had (`had`: the values of its earlier versions; a slider may outlive the term
/// that used it): a typo, answered with bad_field rather than ignored.
std::optional<ErrorReply> check_names(const FunctionVersion& version,
                                      const protocol::Parameters& supplied,
                                      const protocol::Parameters& had = {}) {
    const auto& known = version.tape->params;
    for (const auto& [name, value] : supplied) {
        if (std::find(known.begin(), known.end(), name) != known.end()) continue;
        if (had.contains(name)) continue;
        std::string list;
        for (const std::string& p : known) list += (list.empty() ? "'" : ", '") + p + "'";
        return reject(version.request_id, ErrorCode::bad_field,
                      "parameters: the function has no parameter '" + name + "' (" +
                          (list.empty() ? std::string("it has none") : "its parameters: " + list) +
                          ")");
    }
    return std::nullopt;
}

/// Binds the supplied values to the tape's parameters and builds the field.
std::optional<ErrorReply> bind(FunctionVersion& version) {
    const std::map<std::string, double, std::less<>> values(version.values.begin(),
                                                            version.values.end());
    ParameterBinding binding = bind_parameters(*version.tape, values);
    if (!binding.ok())
        return reject(version.request_id, ErrorCode::bad_field, "parameters: " + *binding.error);
    version.state.parameters.clear();
    for (std::size_t i = 0; i < version.tape->params.size(); ++i)
        version.state.parameters[version.tape->params[i]] = binding.values[i];
    try {
        version.field = make_tape_field(version.tape, std::move(binding.values));
    } catch (const std::invalid_argument& e) {
        return reject(version.request_id, ErrorCode::bad_expression, e.what());
    }
    return std::nullopt;
}

/// Resolves `requested` over `base` field by field and checks it against the limits.
std::optional<ErrorReply> set_constraints(FunctionVersion& version,
                                          const protocol::Constraints& base,
                                          const protocol::Constraints& requested,
                                          const VersionLimits& limits) {
    protocol::Constraints c = base;
    if (requested.triangles) c.triangles = requested.triangles;
    if (requested.max_error) c.max_error = requested.max_error;
    if (requested.error_measure) c.error_measure = requested.error_measure;
    if (*c.triangles > limits.max_triangles) {
        return reject(version.request_id, ErrorCode::budget_too_large,
                      "constraints.triangles: " + std::to_string(*c.triangles) +
                          " exceeds the server's maximum of " +
                          std::to_string(limits.max_triangles));
    }
    auto measure = make_error_measure(*c.error_measure);
    if (!measure) {
        std::string names;
        for (const std::string& name : error_measure_names())
            names += (names.empty() ? "" : ", ") + name;
        return reject(version.request_id, ErrorCode::bad_field,
                      "constraints.error_measure: unknown measure '" + *c.error_measure +
                          "' (known: " + names + ")");
    }
    version.error_measure = std::move(measure);
    version.constraint =
        Constraint::budget_and_error_bound(static_cast<std::size_t>(*c.triangles), *c.max_error);
    version.state.constraints = c;
    return std::nullopt;
}

void set_box(FunctionVersion& version, const protocol::Box& box) {
    version.state.box = box;
    version.box = Box{{box[0], box[2], box[4]}, {box[1], box[3], box[5]}};
}

}  // namespace

VersionResult first_version(const protocol::Create& request, const VersionLimits& limits) {
    FunctionVersion version;
    version.request_id = request.id;
    version.requested = Clock::now();
    version.source = request.source;
    version.values = request.parameters;
    version.state.version = 1;
    set_box(version, request.box);
    const protocol::Constraints defaults{limits.default_triangles, limits.default_max_error,
                                         error_measure_names().front()};
    if (auto error = set_constraints(version, defaults, request.constraints, limits)) return *error;
    if (auto error = compile(version, limits)) return *error;
    if (auto error = check_names(version, request.parameters)) return *error;
    if (auto error = bind(version)) return *error;
    return version;
}

VersionResult next_version(const FunctionVersion& current, const protocol::Update& request,
                           const VersionLimits& limits) {
    FunctionVersion version = current;
    version.request_id = request.id;
    version.requested = Clock::now();
    version.state.version = current.state.version + 1;
    if (request.box) set_box(version, *request.box);
    if (request.constraints) {
        if (auto error =
                set_constraints(version, current.state.constraints, *request.constraints, limits))
            return *error;
    }
    if (request.source) {
        version.source = *request.source;
        if (auto error = compile(version, limits)) return *error;
    }
    if (request.parameters) {
        for (const auto& [name, value] : *request.parameters) version.values[name] = value;
        if (version.values.size() > limits.compile.max_parameters) {
            return reject(request.id, ErrorCode::too_large,
                          "parameters: more than " + std::to_string(limits.compile.max_parameters) +
                              " distinct names over the session's updates");
        }
    }
    if (request.parameters) {
        if (auto error = check_names(version, *request.parameters, current.values)) return *error;
    }
    if (request.source || request.parameters) {
        if (auto error = bind(version)) return *error;
    }
    return version;
}

bool changes_nothing(const FunctionVersion& current, const FunctionVersion& next) {
    return current.source == next.source && current.state.parameters == next.state.parameters &&
           current.state.box == next.state.box &&
           current.state.constraints == next.state.constraints;
}

}  // namespace isomesh::server
