// Hash tables keyed by the 64-bit ids of lattice points, cells and edges (Lattice::key,
// LeafIndex::key, crossing keys): Abseil's Swiss tables (open addressing, one allocation per
// table). Node-based std::unordered_map allocated an entry per value: on a CAD model's octree
// the lookups were a sixth of phase 1's time, and freeing millions of entries alone took a
// quarter of a second (colonnade.vm at depth 7). Iteration order is unspecified (it changes from
// run to run): nothing may depend on it.
#pragma once

#include <cstdint>

#include <absl/container/flat_hash_map.h>
#include <absl/container/flat_hash_set.h>

namespace isomesh {

template <typename Value>
using IdMap = absl::flat_hash_map<std::uint64_t, Value>;
using IdSet = absl::flat_hash_set<std::uint64_t>;

/// Values of f at lattice points, by Lattice::key.
using ValueMap = IdMap<double>;

}  // namespace isomesh
