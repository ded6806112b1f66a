// What the load generator's sessions ask for: a mix of `create` requests (gallery surfaces by
// default), some with a parameter moved like a slider.
//
// A mix file is a JSON array of entries; each entry holds the fields of a protocol `create`
// (`expression` or `vm`, `box`, optional `parameters` and `constraints`; PROTOCOL.md 2.1) and
// optionally:
//   "name":   a label for reports (default "entry N"),
//   "weight": an integer >= 1, how many sessions of each round take this entry (default 1),
//   "slider": {"parameter": "a", "min": 2, "max": 6}: once the first mesh arrives, the session
//             sends `update`s moving parameter `a` back and forth between min and max (the
//             parameter needs a starting value in "parameters").
// Example: [{"name": "sphere", "expression": "x^2+y^2+z^2=a", "parameters": {"a": 4},
//            "box": [-3, 3, -3, 3, -3, 3], "slider": {"parameter": "a", "min": 2, "max": 6}}]
#pragma once

#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "protocol/messages.h"

namespace isomesh::load {

struct Slider {
    std::string parameter;
    double min = 0;
    double max = 1;
};

struct MixEntry {
    std::string name;
    protocol::Create create;  ///< without an id: each session numbers its own requests
    unsigned weight = 1;
    std::optional<Slider> slider;
};

using Mix = std::vector<MixEntry>;

/// The built-in mix: surfaces of the viewer's gallery (the thesis's among them), half of them
/// with a slider. Written in the mix file format (kDefaultMixJson).
extern const std::string_view kDefaultMixJson;
Mix default_mix();

/// Parses a mix file's text. Throws std::runtime_error naming the entry and the problem (bad
/// JSON, an invalid create request as the protocol library judges it, a bad weight or slider).
Mix parse_mix(std::string_view json_text);

/// Reads and parses a mix file; throws std::runtime_error (naming the file) on failure.
Mix load_mix_file(const std::string& path);

/// The entry of the `round`-th session started by virtual user `user` out of `users`: users take
/// the weighted entries in turn, and each new session of a user moves `users` entries further,
/// so the whole mix is used whatever the counts.
const MixEntry& mix_entry(const Mix& mix, std::size_t user, std::size_t users, std::size_t round);

/// `entry` with each parameter moved by up to `jitter` times its value (times 1 for values below
/// 1) and its box grown by up to `jitter` times its size on every side, drawn from `seed`:
/// sessions that ask for meshes of their own (a server's first-mesh cache misses), the same in
/// every run.
MixEntry jittered(const MixEntry& entry, double jitter, std::uint64_t seed);

}  // namespace isomesh::load
