// The network face of the server: one port for HTTP and WebSocket (Boost.Beast).
//   /ws        WebSocket upgrade: the isomesh protocol (net/websocket_connection.h)
//   /healthz   liveness: "ok" while the server answers
//   /readyz    readiness: "ready", or 503 with the reason (draining, the session store down)
//   /metrics   Prometheus text format
//   anything else: the browser client's files (server/static_files.h)
// SIGINT and SIGTERM drain: stop accepting, end sessions with `closed`, let queued frames leave
// (at most the drain timeout), close every connection with a close frame, then run() returns.
#pragma once

#include <cstdint>
#include <memory>

#include "server/config.h"
#include "server/log.h"
#include "server/mesh_service.h"
#include "server/metrics.h"

namespace isomesh::server::net {

class HttpServer {
  public:
    HttpServer(MeshService& service, const ServerConfig& config, Logger& logger, Metrics& metrics);
    ~HttpServer();
    HttpServer(const HttpServer&) = delete;
    HttpServer& operator=(const HttpServer&) = delete;

    /// Binds config.bind_address:config.port; returns the port (chosen by the system for 0).
    /// Throws std::runtime_error when the address cannot be bound.
    std::uint16_t listen();

    /// Serves on config.io_threads threads (this one included) until a signal has drained
    /// everything.
    void run();

  private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
};

}  // namespace isomesh::server::net
