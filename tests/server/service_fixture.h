// What the service tests share: a MeshService with test settings, and helpers that create
// sessions and wait for their meshes through TestConnections.
#pragma once

#include <cstdint>
#include <string>

#include "server/mesh_service.h"
#include "test_connection.h"

namespace isomesh::server::testing {

/// Two workers, quiet logs, three sessions per connection, budgets up to 100,000 triangles.
ServerConfig test_config();

struct Fixture {
    explicit Fixture(ServerConfig c = test_config())
        : config(c), logger(c.log_level), service(config, logger, metrics) {}
    ServerConfig config;
    Logger logger;
    Metrics metrics;
    MeshService service;
};

/// A create request on the box [-3, 3]^3.
protocol::Create create_request(std::string expression, std::uint64_t triangles,
                                protocol::Parameters parameters = {}, std::int64_t id = 1);

/// Creates a session and returns its control id (failing the test when there is none).
protocol::SessionId create(TestConnection& connection, const protocol::Create& request);

/// The `created` reply to request `id`, if it came.
const protocol::Created* created_reply(const TestConnection& connection, std::int64_t id);

/// Waits until `connection` holds the final mesh of `version`.
bool wait_converged(TestConnection& connection, const protocol::SessionId& session,
                    std::uint32_t version = 1);

/// The error replying to request `id`, if any.
const protocol::ErrorReply* error_for(const TestConnection& connection, std::int64_t id);

/// Sends `message` and waits for the reply (or error) echoing `id`.
bool request(TestConnection& connection, const protocol::ClientMessage& message, std::int64_t id);

}  // namespace isomesh::server::testing
