// New sessions' first meshes, kept for the next session that asks for the same: the same request
// gives the same mesh (determinism), so sessions opening the same example (a gallery, a shared
// link, a class of students) share the work of the first frame.
//
// The key is the canonical request (first_mesh_key): the compiled function (the tape, after
// parsing: spelling and spacing do not matter), the parameter values, the box, the constraints,
// the function version and the protocol versions of the subscribers. An entry holds what a
// session's first turn makes: the pipeline's first mesh, the frame mirrors (wire_mesh.h,
// wire_mesh_v2.h) and the keyframes, and the `progress` that follows them. A session that finds
// its request here sends the cached keyframe at once and makes its own first step in a later
// turn; if that step's mesh differs from the cached one (a first step cut by its time budget
// rather than by its cell count), the session sends its own mesh as a keyframe then, so every
// client still ends with the mesh the request gives.
//
// Bounded: at most max_entries entries and max_bytes bytes (estimated), least recently used
// evicted first. A request is kept the second time it is made (seen_before): sessions asking for
// meshes of their own (a user's own equation, a slider's values) pay no copy into the cache.
// Thread-safe.
#pragma once

#include <array>
#include <cstdint>
#include <list>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <unordered_map>

#include <absl/container/flat_hash_set.h>

#include "protocol/messages.h"
#include "refine/refiner.h"
#include "server/client.h"
#include "server/function_version.h"
#include "server/wire_mesh.h"
#include "server/wire_mesh_v2.h"

namespace isomesh::server {

/// A session's first turn, as made for the request of its key.
struct FirstMesh {
    RefinedMesh mesh;  ///< the pipeline's first mesh: a session's own first step must match it
    WireMesh wire;
    WireMeshV2 wire_v2;
    /// The keyframe by protocol version (index 0: version 1), sequence 0, for every protocol
    /// version of the key; its session id and timestamp are the first session's.
    std::array<std::shared_ptr<const Bytes>, 2> keyframes;
    protocol::Progress progress;  ///< what follows the keyframe (session id to replace)
    std::uint64_t bytes = 0;      ///< estimated size, key included
};

/// The key of `version` as the first version of a session whose subscribers speak the protocol
/// versions in `protocols` (bit 0: version 1, bit 1: version 2); nothing when the request is too
/// large to be worth keeping (a long .vm program).
std::optional<std::string> first_mesh_key(const FunctionVersion& version, unsigned protocols);

/// Estimates an entry's bytes (its mesh, mirrors and frames) and stores them in first.bytes.
void measure(FirstMesh& first, const std::string& key);

class FirstMeshCache {
  public:
    FirstMeshCache(std::size_t max_entries, std::uint64_t max_bytes)
        : max_entries_(max_entries), max_bytes_(max_bytes) {}

    /// The entry of `key`, now the most recently used; null when there is none.
    std::shared_ptr<const FirstMesh> find(const std::string& key);
    /// True when `key` was asked for before (by hash, among the last few times max_entries keys);
    /// records it otherwise.
    bool seen_before(const std::string& key);
    /// Keeps `first` under `key` (replacing an entry of that key), evicting the least recently
    /// used entries beyond the bounds; an entry larger than max_bytes alone is not kept.
    void insert(const std::string& key, std::shared_ptr<const FirstMesh> first);

    std::size_t entries() const;
    std::uint64_t bytes() const;

  private:
    using Order = std::list<std::string>;  // most recently used first
    struct Slot {
        std::shared_ptr<const FirstMesh> first;
        Order::iterator position;
    };
    void evict_beyond_bounds();

    const std::size_t max_entries_;
    const std::uint64_t max_bytes_;
    mutable std::mutex mutex_;
    Order order_;
    std::unordered_map<std::string, Slot> slots_;
    std::uint64_t bytes_ = 0;
    absl::flat_hash_set<std::size_t> seen_;  // hashes of keys asked for, cleared when full
};

}  // namespace isomesh::server
