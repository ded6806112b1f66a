// `isomesh mesh --server ws://HOST:PORT/ws`: the same request meshed by a running isomesh-server
// instead of in-process. The CLI sends one `create`, applies every frame to a MeshReplica (the
// protocol library's client state) until `converged`, and writes the replica's mesh through the
// same writers as an in-process run: same triangles and vertices, positions and normals as the
// protocol carries them (positions on the session's 14-bit grid, octahedral normals).
#pragma once

#include <span>
#include <string>
#include <string_view>

#include "mesh/mesh.h"
#include "protocol/messages.h"
#include "protocol/replica.h"
#include "refine_options.h"

namespace isomesh::cli {

inline constexpr std::string_view kServerUsage =
    R"(  --server URL        mesh on a running isomesh-server (ws://HOST:PORT/ws) instead of
                      in-process: the same mesh, positions on the protocol's 14-bit grid;
                      phase 1 always starts at the server's depths (as --depth 3,9 here)
)";

/// The `create` for an in-process run's arguments: `source` (an expression or `@model.vm`, whose
/// text is sent), the `--param` items, the meshing box and the refinement options. Without
/// --triangles or --max-error the server is asked for phase 1 alone (an error bound no triangle
/// exceeds), which it starts at its own depths (those of a refining run here,
/// kRefinePhase1MinDepth); with --max-error alone, for the in-process run's triangle cap. Throws
/// UsageError for a sampled grid (`@grid.iso`: the protocol carries functions only) or an
/// unreadable model file.
protocol::Create server_request(std::string_view source,
                                std::span<const std::string_view> param_items, const Box& box,
                                const RefineOptions& refine);

/// The replica's mesh: vertices in ascending global id order, triangles in ascending id order
/// (corners as decoded, orientation kept).
Mesh replica_mesh(const protocol::MeshReplica& replica);

/// Meshes `create` on the server at `url` (a ws:// URL) and writes the result to `output`;
/// prints what went wrong (connection, server error, timeout) and returns the exit status: 0, or
/// 1 on failure. `stats`: print one JSON line (triangles, vertices, the server's first_mesh_ms,
/// total_ms, errors, splits, merges, and frames and bytes received). Throws UsageError for a
/// malformed URL.
int mesh_on_server(std::string_view url, const protocol::Create& create, const std::string& output,
                   bool stats);

}  // namespace isomesh::cli
