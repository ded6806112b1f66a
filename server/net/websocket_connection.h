// One WebSocket connection (Beast's advanced server is the model): the stream lives on its own
// strand; a read is always pending, so pings, pongs and close frames are handled; at most one
// write is in flight, taken from the client's OutputQueue (server/output_queue.h), which holds
// the byte budget. Every error ends the connection the same way: fail() logs it and end() tells
// the service that the client is gone.
//
// Included only by the net/*.cpp files: Beast compiles slowly.
#pragma once

#include <memory>
#include <mutex>
#include <optional>
#include <set>

#include <boost/asio/ip/tcp.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/http.hpp>
#include <boost/beast/websocket.hpp>

#include "server/mesh_service.h"

namespace isomesh::server::net {

namespace asio = boost::asio;
namespace beast = boost::beast;
namespace http = beast::http;
namespace websocket = beast::websocket;
using tcp = asio::ip::tcp;

/// Anything the server must close at shutdown: WebSocket connections and idle HTTP sessions.
class Closable {
  public:
    virtual ~Closable() = default;
    /// Finishes what is queued, then closes; called from any thread.
    virtual void shutdown() = 0;
    /// Closes the socket now (the drain timeout passed).
    virtual void abort() = 0;
};

/// The open connections, for shutdown and the connection limit.
class ConnectionSet {
  public:
    void add(const std::shared_ptr<Closable>& connection);
    void remove(const Closable* connection);
    std::size_t size() const;
    std::vector<std::shared_ptr<Closable>> all() const;

  private:
    mutable std::mutex mutex_;
    std::map<const Closable*, std::weak_ptr<Closable>> connections_;
};

/// What connections share.
struct NetContext {
    MeshService& service;
    Logger& logger;
    Metrics& metrics;
    const ServerConfig& config;
    ConnectionSet& websockets;
    ConnectionSet& http_sessions;
};

class WebSocketConnection final : public Closable,
                                  public std::enable_shared_from_this<WebSocketConnection> {
  public:
    WebSocketConnection(tcp::socket&& socket, NetContext& context);
    ~WebSocketConnection() override;

    /// Accepts the upgrade `request` (whose URL gave `route`) and starts reading.
    void start(http::request<http::string_body> request, std::optional<Route> route);
    void shutdown() override;
    void abort() override;

  private:
    void on_accept(beast::error_code ec);
    void do_read();
    void on_read(beast::error_code ec, std::size_t bytes);
    /// From any thread: the output queue has something while the writer was idle.
    void wake();
    void do_write();
    void on_write(beast::error_code ec, std::size_t bytes);
    void do_close(websocket::close_code code);
    void on_close(beast::error_code ec);
    void fail(beast::error_code ec, const char* what);
    void end();

    websocket::stream<beast::tcp_stream> ws_;
    NetContext& context_;
    beast::flat_buffer buffer_;
    std::shared_ptr<Client> client_;
    std::optional<Outgoing> writing_;  // the message in flight
    std::string remote_;
    std::optional<Route> route_;
    bool closing_ = false;  // close once the queue is empty
    bool close_started_ = false;
    bool ended_ = false;
};

}  // namespace isomesh::server::net
