// isomesh-protocol-sample: sample output of the protocol library, for checks written in other
// languages and for measuring the codec.
//
//   isomesh-protocol-sample frames DIR   writes a keyframe and deltas of a refining sphere as
//                                        DIR/NNN.bin, and DIR/frames.json: what the C++ decoder
//                                        reads from each frame, and the final mesh
//   isomesh-protocol-sample frames-v2 DIR the same session in protocol version 2 (PROTOCOL.md
//                                        4.5): a keyframe with octahedral normals, deltas
//                                        encoded against what a version-2 client holds
//   isomesh-protocol-sample messages DIR writes one sample of every control message as
//                                        DIR/<type>.json
//   isomesh-protocol-sample stats        prints bytes per triangle of deltas of several sizes
//   isomesh-protocol-sample echo-id JSON prints {"accepted": true|false}: whether the C++ parser
//                                        takes JSON (a value) as the id of a ping
#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <string>
#include <unordered_map>

#include <nlohmann/json.hpp>

#include "protocol/delta_v2.h"
#include "protocol/delta_v2_geometry.h"
#include "protocol/frame.h"
#include "protocol/messages.h"
#include "protocol/replica.h"
#include "protocol/tools/sample_mesh.h"

namespace {

namespace fs = std::filesystem;
using namespace isomesh::protocol;
using nlohmann::ordered_json;

constexpr std::uint64_t kSampleTime = 1'700'000'000'000'000;

void write_bytes(const fs::path& path, const std::vector<std::uint8_t>& bytes) {
    std::ofstream out(path, std::ios::binary);
    out.write(reinterpret_cast<const char*>(bytes.data()),
              static_cast<std::streamsize>(bytes.size()));
}

void write_text(const fs::path& path, const std::string& text) {
    std::ofstream(path) << text << '\n';
}

ordered_json triangles_json(const std::vector<FrameTriangle>& triangles) {
    ordered_json out = ordered_json::array();
    for (const auto& t : triangles) {
        out.push_back({t.id, t.vertices[0], t.vertices[1], t.vertices[2]});
    }
    return out;
}

ordered_json vertices_json(const std::vector<Vertex>& vertices) {
    ordered_json out = ordered_json::array();
    for (const Vertex& v : vertices) {
        out.push_back(
            {v.id, v.position.x, v.position.y, v.position.z, v.normal.x, v.normal.y, v.normal.z});
    }
    return out;
}

ordered_json frame_json(const std::string& file, const DecodedFrame& frame) {
    const FrameHeader& h = frame.header;
    return {{"file", file},
            {"kind", h.kind == FrameKind::keyframe ? "keyframe" : "delta"},
            {"flags", h.flags},
            {"session", h.session.to_hex()},
            {"sequence", h.sequence},
            {"timestamp_us", h.timestamp_us},
            {"function_version", h.function_version},
            {"removed", frame.removed},
            {"vertices", vertices_json(frame.vertices)},
            {"triangles", triangles_json(frame.triangles)}};
}

/// Writes the sample session's frames and what the C++ decoder and replica make of them.
int write_frames(const fs::path& dir) {
    fs::create_directories(dir);
    const samples::SampleSession session = samples::refining_sphere_session();
    MeshReplica replica;
    ordered_json manifest = {{"frames", ordered_json::array()}};
    for (std::size_t i = 0; i < session.frames.size(); ++i) {
        const std::string name = "frame" + std::to_string(i) + ".bin";
        write_bytes(dir / name, session.frames[i]);
        auto decoded = decode_frame(session.frames[i]);
        if (!decoded || replica.apply(decoded.value()) != MeshReplica::Outcome::applied) {
            return std::fprintf(stderr, "sample frame %zu does not apply\n", i), 1;
        }
        manifest["frames"].push_back(frame_json(name, decoded.value()));
    }
    if (replica.sorted_triangles() != session.final_triangles) {
        return std::fprintf(stderr, "replica differs from the sender's mesh\n"), 1;
    }
    manifest["final_triangles"] = triangles_json(session.final_triangles);
    std::vector<Vertex> final_vertices;
    for (const auto& [id, vertex] : replica.vertices()) final_vertices.push_back(vertex);
    std::sort(final_vertices.begin(), final_vertices.end(),
              [](const Vertex& a, const Vertex& b) { return a.id < b.id; });
    manifest["final_vertices"] = vertices_json(final_vertices);
    write_text(dir / "frames.json", manifest.dump());
    std::printf("wrote %zu frames to %s\n", session.frames.size(), dir.c_str());
    return 0;
}

/// The version-2 delta that takes a version-2 client from `held` to where the version-1 delta
/// `v1` takes a version-1 client: the same removals, the vertices it lacks as new ones (wire ids
/// from next_vertex on, in version-1 id order), held ones on another grid point as moved.
DeltaV2Change as_v2_change(const DecodedFrame& v1, const HeldMesh& held, const GridMath& math,
                           std::unordered_map<std::uint32_t, std::uint32_t>& wire_vertex,
                           const std::unordered_map<std::uint64_t, std::uint64_t>& wire_triangle,
                           std::uint32_t next_vertex) {
    DeltaV2Change change;
    for (std::uint64_t id : v1.removed) change.removed.push_back(wire_triangle.at(id));
    std::vector<Vertex> sorted = v1.vertices;
    std::sort(sorted.begin(), sorted.end(),
              [](const Vertex& a, const Vertex& b) { return a.id < b.id; });
    for (const Vertex& v : sorted) {
        auto it = wire_vertex.find(v.id);
        const Vertex* known = it == wire_vertex.end() ? nullptr : held.vertex(it->second);
        if (!known) {
            const auto id = static_cast<std::uint32_t>(next_vertex + change.new_vertices.size());
            wire_vertex[v.id] = id;
            change.new_vertices.push_back({id, v.position, v.normal});
        } else if (math.quantize(v.position) != math.recover(known->position)) {
            change.moved_vertices.push_back({it->second, v.position, v.normal});
        }
    }
    for (const FrameTriangle& t : v1.triangles) {
        change.added.push_back({{wire_vertex.at(t.vertices[0]), wire_vertex.at(t.vertices[1]),
                                 wire_vertex.at(t.vertices[2])}});
    }
    return change;
}

/// The sample session in version 2 (PROTOCOL.md 4.5): its keyframe with a grid block and
/// octahedral normals, each delta encoded against what a version-2 client holds; frames.json says
/// what the C++ decoder reads from each, and the final mesh.
int write_frames_v2(const fs::path& dir) {
    fs::create_directories(dir);
    const samples::SampleSession session = samples::refining_sphere_session();
    MeshEncoding encoding;
    encoding.grid = QuantizationGrid::for_box({-1.5, 1.5, -1.5, 1.5, -1.5, 1.5});
    encoding.octahedral_normals = true;
    const GridMath math(encoding.grid);
    HeldMesh held;
    std::unordered_map<std::uint32_t, std::uint32_t> wire_vertex;    // version 1 -> version 2
    std::unordered_map<std::uint64_t, std::uint64_t> wire_triangle;  // version 1 -> version 2
    std::uint32_t next_vertex = 0;
    std::uint64_t next_triangle = 0;
    ordered_json manifest = {{"frames", ordered_json::array()}};
    for (std::size_t i = 0; i < session.frames.size(); ++i) {
        const DecodedFrame v1 = decode_frame(session.frames[i]).value();
        FrameInfo info = v1.header;
        info.protocol_version = 2;
        std::vector<std::uint8_t> bytes;
        if (info.kind == FrameKind::keyframe) {
            std::vector<Triangle> triangles;
            std::vector<std::uint64_t> ids;
            for (const FrameTriangle& t : v1.triangles) {
                triangles.push_back({t.vertices});
                ids.push_back(t.id);
                wire_triangle[t.id] = t.id;
                next_triangle = std::max(next_triangle, t.id + 1);
            }
            for (const Vertex& v : v1.vertices) {
                wire_vertex[v.id] = v.id;
                next_vertex = std::max(next_vertex, v.id + 1);
            }
            bytes = encode_keyframe(info, v1.vertices, triangles, ids, encoding).value().bytes;
        } else {
            const DeltaV2Change change =
                as_v2_change(v1, held, math, wire_vertex, wire_triangle, next_vertex);
            auto encoded =
                encode_delta_v2(info, held, change, next_triangle, next_vertex, encoding.grid);
            if (!encoded) return std::fprintf(stderr, "%s\n", encoded.error().message.c_str()), 1;
            bytes = encoded.value().bytes;
            for (std::size_t t = 0; t < v1.triangles.size(); ++t)
                wire_triangle[v1.triangles[t].id] = encoded.value().triangle_ids[t];
            for (const auto& [was, now] : encoded.value().renamed) {
                for (auto& [v1_id, wire] : wire_triangle) {
                    if (wire == was) wire = now;
                }
            }
            next_triangle = encoded.value().next_triangle_id;
            next_vertex = encoded.value().next_vertex_id;
        }
        auto decoded = info.kind == FrameKind::keyframe
                           ? decode_frame(bytes)
                           : decode_delta_v2(bytes, held, encoding.grid);
        if (!decoded) return std::fprintf(stderr, "v2 frame %zu does not decode\n", i), 1;
        const std::string name = "frame" + std::to_string(i) + ".bin";
        write_bytes(dir / name, bytes);
        manifest["frames"].push_back(frame_json(name, decoded.value()));
        held.apply(decoded.value());
    }
    std::vector<FrameTriangle> final_triangles;
    for (const auto& [id, corners] : held.triangles()) final_triangles.push_back({id, corners});
    std::sort(final_triangles.begin(), final_triangles.end(),
              [](const FrameTriangle& a, const FrameTriangle& b) { return a.id < b.id; });
    manifest["final_triangles"] = triangles_json(final_triangles);
    write_text(dir / "frames.json", manifest.dump());
    std::printf("wrote %zu version-2 frames to %s\n", session.frames.size(), dir.c_str());
    return 0;
}

std::vector<std::pair<std::string, std::string>> sample_messages() {
    const SessionId session = samples::sample_session_id();
    const Box box = {-2, 2, -2, 2, -2, 2};
    const Constraints all{20000, 0.001, "epsilon4"};
    const SessionState state{3, "x^2+y^2+z^2=a", {{"a", 4}}, box, all};
    std::vector<std::pair<std::string, std::string>> out;
    auto client = [&](MessageType type, const ClientMessage& m) {
        out.emplace_back(std::string(to_string(type)), serialize(m));
    };
    auto server = [&](MessageType type, const ServerMessage& m) {
        out.emplace_back(std::string(to_string(type)), serialize(m));
    };
    client(MessageType::create, Create{1,
                                       {Source::Kind::expression, "x^2+y^2+z^2=a"},
                                       {{"a", 4}},
                                       box,
                                       {20000, std::nullopt, std::nullopt}});
    client(MessageType::update, Update{"slider-7", session, std::nullopt, Parameters{{"a", 4.5}},
                                       std::nullopt, std::nullopt});
    client(MessageType::subscribe, Subscribe{2, session});
    client(MessageType::unsubscribe, Unsubscribe{3, session});
    client(MessageType::pause, Pause{4, session});
    client(MessageType::resume, Resume{5, session});
    client(MessageType::close, Close{6, session});
    client(MessageType::resync, Resync{std::nullopt, session});
    client(MessageType::ping, Ping{8});
    SessionId view = session;
    view.bytes[0] ^= 0xFF;
    const ServerLimits limits{1 << 20, 16, 2'000'000, 1u << 30, 10.0, 3600.0, 3600.0, 30.0};
    server(MessageType::created, Created{1, session, state, view, Access::control});
    server(MessageType::updated, Updated{"slider-7", session, state, view, Access::control});
    server(MessageType::subscribed, Subscribed{2, view, state, std::nullopt, Access::view});
    server(MessageType::ack, Ack{4, MessageType::pause, session});
    server(MessageType::pong, Pong{8, kSampleTime, limits});
    server(MessageType::progress, Progress{session, 3, 12, 8000, 0.02, 1.5, 250000});
    server(MessageType::converged,
           Converged{session, 3, 40, 20000, 0.001, 0.9, 9500, 120, 2.5, 41.0});
    server(MessageType::error, ErrorReply{1, std::nullopt, ErrorCode::bad_expression,
                                          "unexpected ')' at column 12", 12});
    server(MessageType::closed, Closed{session, Closed::Reason::expired});
    return out;
}

int write_messages(const fs::path& dir) {
    fs::create_directories(dir);
    for (const auto& [type, text] : sample_messages()) write_text(dir / (type + ".json"), text);
    std::printf("wrote %zu messages to %s\n", sample_messages().size(), dir.c_str());
    return 0;
}

struct Measure {
    std::size_t triangles = 0;
    std::size_t frame_bytes = 0;
    std::size_t mesh_bytes = 0;
};

/// A refinement-like delta: `count / 4` triangles of a cap of a fine sphere split 1-to-4.
Measure measure_split_delta(const samples::SampleMesh& sphere, std::size_t count,
                            const MeshEncoding& encoding) {
    const auto chosen = samples::cap(sphere, {0.2f, 0.3f, 1}, count / 4);
    const auto split =
        samples::subdivide(sphere, chosen, static_cast<std::uint32_t>(sphere.vertices.size()));
    std::vector<Vertex> all = sphere.vertices;
    all.insert(all.end(), split.vertices.begin(), split.vertices.end());
    std::vector<std::uint64_t> removed(chosen.begin(), chosen.end());
    FrameInfo info{FrameKind::delta, 0, samples::sample_session_id(), 1, kSampleTime, 1};
    auto frame = encode_delta(info, {removed, all, split.triangles, 1 << 20}, encoding);
    if (!frame) return {};
    const auto header = read_frame_header(frame.value().bytes);
    return {split.triangles.size(), frame.value().bytes.size(), header.value().mesh_bytes};
}

int print_stats() {
    const auto sphere = samples::icosphere(6, 1.0f);  // 81,920 triangles
    std::printf("delta = split 1-to-4 of a cap of an icosphere (81,920 triangles), box [-1,1]^3\n");
    std::printf("%5s %6s %9s %10s %10s %12s\n", "bits", "speed", "triangles", "frame B", "mesh B",
                "frame B/tri");
    for (int bits : {14, 16}) {
        for (int speed : {2, 5}) {
            MeshEncoding encoding;
            encoding.grid = QuantizationGrid::for_box({-1, 1, -1, 1, -1, 1}, bits);
            encoding.encoding_speed = speed;
            encoding.decoding_speed = speed;
            for (std::size_t count : {200u, 1000u, 10000u}) {
                const Measure m = measure_split_delta(sphere, count, encoding);
                std::printf("%5d %6d %9zu %10zu %10zu %12.2f\n", bits, speed, m.triangles,
                            m.frame_bytes, m.mesh_bytes,
                            double(m.frame_bytes) / double(m.triangles));
            }
        }
    }
    return 0;
}

int echo_id(const std::string& id_json) {
    const auto parsed = parse_client_message(R"({"v":1,"type":"ping","id":)" + id_json + "}");
    std::printf("{\"accepted\": %s}\n", parsed ? "true" : "false");
    return 0;
}

}  // namespace

int main(int argc, char** argv) {
    const std::string usage =
        "usage: isomesh-protocol-sample frames DIR | frames-v2 DIR | messages DIR | stats | "
        "echo-id JSON\n";
    if (argc == 3 && std::string(argv[1]) == "frames") return write_frames(argv[2]);
    if (argc == 3 && std::string(argv[1]) == "frames-v2") return write_frames_v2(argv[2]);
    if (argc == 3 && std::string(argv[1]) == "messages") return write_messages(argv[2]);
    if (argc == 2 && std::string(argv[1]) == "stats") return print_stats();
    if (argc == 3 && std::string(argv[1]) == "echo-id") return echo_id(argv[2]);
    std::cerr << usage;
    return 2;
}
