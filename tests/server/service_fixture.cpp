#include "service_fixture.h"

#include <gtest/gtest.h>

namespace isomesh::server::testing {

ServerConfig test_config() {
    ServerConfig config;
    config.worker_threads = 2;
    config.log_level = LogLevel::error;
    config.max_sessions_per_connection = 3;
    config.max_triangles = 100'000;
    return config;
}

protocol::Create create_request(std::string expression, std::uint64_t triangles,
                                protocol::Parameters parameters, std::int64_t id) {
    protocol::Create c;
    c.id = id;
    c.source.text = std::move(expression);
    c.parameters = std::move(parameters);
    c.box = {-3, 3, -3, 3, -3, 3};
    c.constraints.triangles = triangles;
    return c;
}

const protocol::Created* created_reply(const TestConnection& connection, std::int64_t id) {
    return connection.find<protocol::Created>(protocol::RequestId{id});
}

protocol::SessionId create(TestConnection& connection, const protocol::Create& request) {
    connection.send(request);
    EXPECT_TRUE(connection.wait_for([&] {
        return connection.find<protocol::Created>(request.id) ||
               connection.find<protocol::ErrorReply>(request.id);
    }));
    const auto* created = connection.find<protocol::Created>(request.id);
    EXPECT_NE(created, nullptr);
    return created ? created->session : protocol::SessionId{};
}

bool wait_converged(TestConnection& connection, const protocol::SessionId& session,
                    std::uint32_t version) {
    return connection.wait_for([&] {
        const auto* c = connection.converged(session, version);
        return c && connection.replicas[session].synchronized() &&
               connection.replicas[session].sequence() >= c->sequence;
    });
}

const protocol::ErrorReply* error_for(const TestConnection& connection, std::int64_t id) {
    return connection.find<protocol::ErrorReply>(protocol::RequestId{id});
}

bool request(TestConnection& connection, const protocol::ClientMessage& message, std::int64_t id) {
    connection.send(message);
    return connection.wait_for([&] {
        for (const auto& m : connection.messages) {
            const bool answers = std::visit(
                [&](const auto& reply) {
                    if constexpr (requires { reply.id; })
                        return reply.id == protocol::RequestId{id};
                    return false;
                },
                m);
            if (answers) return true;
        }
        return false;
    });
}

}  // namespace isomesh::server::testing
