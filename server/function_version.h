// Function versions: what a `create` or an `update` asks a session to mesh, compiled and checked
// before any work starts, so that every mistake in a request is answered at once by an `error`
// (bad_expression with the parser's column, bad_field, budget_too_large).
#pragma once

#include <cstdint>
#include <memory>
#include <optional>

#include "eval/evaluator.h"
#include "expr/compile.h"
#include "protocol/messages.h"
#include "refine/constraints.h"
#include "refine/error_measures.h"
#include "server/clock.h"
#include "tape/tape.h"

namespace isomesh::server {

struct VersionLimits {
    std::uint64_t max_triangles = 2'000'000;
    std::uint64_t default_triangles = 20'000;
    double default_max_error = 0.0;  ///< 0: no error bound
    CompileLimits compile;
};

struct FunctionVersion {
    std::optional<protocol::RequestId> request_id;  ///< of the request that made this version
    Clock::time_point requested{};
    protocol::Source source;
    protocol::Parameters values;   ///< every value supplied so far (state lists the used ones)
    protocol::SessionState state;  ///< as replied: version number, box, resolved constraints
    std::shared_ptr<const Tape> tape;
    std::shared_ptr<const Field> field;
    Box box;
    Constraint constraint;
    std::shared_ptr<const ErrorMeasure> error_measure;
};

using VersionResult = protocol::Result<FunctionVersion, protocol::ErrorReply>;

/// Version 1 of a new session.
VersionResult first_version(const protocol::Create& request, const VersionLimits& limits);

/// The version after `current`: `request`'s fields replace or merge into `current`'s (PROTOCOL.md,
/// `update`); the tape is recompiled only for a new source and the field rebuilt only for a new
/// source or new parameter values (otherwise it is shared, so the session knows nothing changed).
VersionResult next_version(const FunctionVersion& current, const protocol::Update& request,
                           const VersionLimits& limits);

/// True when `next` meshes exactly what `current` does (same source, parameter values, box and
/// constraints): an update that changes nothing makes no new version.
bool changes_nothing(const FunctionVersion& current, const FunctionVersion& next);

}  // namespace isomesh::server
