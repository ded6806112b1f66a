#include "test_connection.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <bit>
#include <map>
#include <thread>

#include "support/grid_match.h"

namespace isomesh::server::testing {

TestConnection::TestConnection(MeshService& service, std::optional<Route> route)
    : service_(service) {
    client = service.connect({}, route);
}

TestConnection::~TestConnection() {
    disconnect();
}

void TestConnection::send(std::string_view text) {
    service_.receive(client, text);
}

void TestConnection::send(const protocol::ClientMessage& message) {
    send(protocol::serialize(message, version));
}

void TestConnection::pump() {
    if (!reading) return;
    while (auto message = client->queue().next()) {
        receive(*message);
        const auto stalled = client->queue().written();
        if (!stalled.empty()) service_.catch_up(client, stalled);
    }
}

bool TestConnection::wait_for(const std::function<bool()>& done, double seconds) {
    const auto end = Clock::now() + std::chrono::duration<double>(seconds);
    for (;;) {
        pump();
        if (done()) return true;
        if (Clock::now() > end) return false;
        std::this_thread::sleep_for(std::chrono::milliseconds(1));
    }
}

void TestConnection::disconnect() {
    if (client) service_.disconnect(client);
}

const protocol::Converged* TestConnection::converged(const protocol::SessionId& session,
                                                     std::uint32_t version) const {
    for (const auto& message : messages) {
        const auto* c = std::get_if<protocol::Converged>(&message);
        if (c && c->session == session && c->version == version) return c;
    }
    return nullptr;
}

void TestConnection::receive(const Outgoing& message) {
    bytes_received += message.size();
    if (!message.binary()) {
        auto parsed = protocol::parse_server_message(*message.text);
        ASSERT_TRUE(parsed.ok()) << *message.text;
        messages.push_back(parsed.value());
        received.emplace_back(parsed.value());
        return;
    }
    auto header = protocol::read_frame_header(*message.frame);
    ASSERT_TRUE(header.ok()) << header.error().message;
    frames.push_back(header.value());
    received.emplace_back(header.value());
    auto outcome = replicas[header.value().session].receive(*message.frame);
    ASSERT_TRUE(outcome.ok()) << outcome.error().message;
    outcomes.push_back(outcome.value());
}

std::vector<std::array<std::uint32_t, 3>> canonical_triangles(const protocol::MeshReplica& mesh) {
    std::vector<std::array<std::uint32_t, 3>> out;
    for (const auto& [id, v] : mesh.triangles()) {
        const auto first = std::min_element(v.begin(), v.end()) - v.begin();
        out.push_back({v[first], v[(first + 1) % 3], v[(first + 2) % 3]});
    }
    std::sort(out.begin(), out.end());
    return out;
}

std::vector<std::array<std::uint32_t, 9>> position_triangles(const protocol::MeshReplica& mesh) {
    std::vector<std::array<std::uint32_t, 9>> out;
    for (const auto& [id, v] : mesh.triangles()) {
        std::array<std::array<std::uint32_t, 3>, 3> corners;
        for (int c = 0; c < 3; ++c) {
            const glm::vec3 p = mesh.vertices().at(v[c]).position;
            corners[c] = {std::bit_cast<std::uint32_t>(p.x), std::bit_cast<std::uint32_t>(p.y),
                          std::bit_cast<std::uint32_t>(p.z)};
        }
        const auto first = std::min_element(corners.begin(), corners.end()) - corners.begin();
        std::array<std::uint32_t, 9> t;
        for (int c = 0; c < 3; ++c)
            std::copy(corners[(first + c) % 3].begin(), corners[(first + c) % 3].end(),
                      t.begin() + 3 * c);
        out.push_back(t);
    }
    std::sort(out.begin(), out.end());
    return out;
}

std::string compare_on_grid(const protocol::MeshReplica& replica, const Mesh& mesh,
                            const protocol::QuantizationGrid& grid) {
    Mesh got;
    std::map<std::uint32_t, std::uint32_t> index_of;
    for (const auto& [id, vertex] : replica.vertices()) {
        index_of[id] = static_cast<std::uint32_t>(got.positions.size());
        got.positions.push_back(vertex.position);
        got.normals.push_back(vertex.normal);
    }
    for (const auto& [id, t] : replica.triangles())
        got.triangles.push_back({index_of.at(t[0]), index_of.at(t[1]), index_of.at(t[2])});
    return test::compare_on_grid(got, mesh, grid);
}

bool watertight(const protocol::MeshReplica& mesh) {
    std::map<std::pair<std::uint32_t, std::uint32_t>, int> directed;
    for (const auto& [id, v] : mesh.triangles()) {
        for (int e = 0; e < 3; ++e) ++directed[{v[e], v[(e + 1) % 3]}];
    }
    for (const auto& [edge, uses] : directed) {
        if (uses != 1) return false;
        auto opposite = directed.find({edge.second, edge.first});
        if (opposite == directed.end() || opposite->second != 1) return false;
    }
    return !directed.empty();
}

}  // namespace isomesh::server::testing
