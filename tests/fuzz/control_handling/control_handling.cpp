// libFuzzer target: the server's handling of control messages (server/mesh_service.h), past the
// parser that tests/fuzz/control_message covers: sessions created, updated, subscribed, paused,
// resynced and closed in any order, by a connection whose output is written out as the network
// would. Every message must get its reply, nothing may crash, hang or leak.
//
// Input: messages separated by newlines. "$S" in a message stands for the id of the session the
// connection created last, so that the fuzzer reaches the paths that need a live session id.
#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>

#include "server/mesh_service.h"

namespace {

using namespace isomesh::server;

ServerConfig fuzz_config() {
    ServerConfig config;
    config.worker_threads = 1;
    config.log_level = LogLevel::error;
    config.max_message_bytes = 4096;
    config.max_sessions_per_connection = 4;
    config.max_triangles = 2000;
    config.default_triangles = 300;
    config.eval_timeout_ms = 200;
    config.orphan_timeout_s = 0;
    return config;
}

struct Server {
    ServerConfig config = fuzz_config();
    Logger logger{config.log_level};
    Metrics metrics;
    MeshService service{config, logger, metrics};
};

/// Writes out everything queued; returns the id of the last `created` session seen, if any.
void drain(Client& client, std::string& last_session) {
    while (auto message = client.queue().next()) {
        if (!message->binary()) {
            const std::string& text = *message->text;
            if (text.find("\"type\":\"created\"") != std::string::npos) {
                const auto at = text.find("\"session\":\"");
                if (at != std::string::npos) last_session = text.substr(at + 11, 32);
            }
        }
        client.queue().written();
    }
}

std::string substitute(std::string_view message, const std::string& session) {
    std::string out;
    for (std::size_t i = 0; i < message.size(); ++i) {
        if (message.substr(i, 2) == "$S") {
            out += session;
            ++i;
        } else {
            out += message[i];
        }
    }
    return out;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    static Server* server = new Server();  // one service (and its threads) for the whole run
    auto client = server->service.connect({});
    std::string last_session(32, '0');
    std::string_view input(reinterpret_cast<const char*>(data), size);
    while (!input.empty()) {
        const std::size_t end = input.find('\n');
        const std::string_view message = input.substr(0, end);
        server->service.receive(client, substitute(message, last_session));
        drain(*client, last_session);
        if (end == std::string_view::npos) break;
        input.remove_prefix(end + 1);
    }
    server->service.disconnect(client);
    return 0;
}
