// One WebSocket connection (Beast's advanced server is the model): the stream lives on its own
// strand; a read is always pending, so pings, pongs and close frames are handled; at most one
// write is in flight, taken from the client's OutputQueue (server/output_queue.h), which holds
// the byte budget. Every error ends the connection the same way: fail() logs it and end() tells
// the service that the client is gone.
//
// Messages are read in pieces, so that one over the size limit is not kept: its first bytes
// (up to the limit) are kept and the rest only scanned for the request id, then it is answered
// with too_large and the connection stays open (PROTOCOL.md, 7).
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

#include "protocol/messages.h"
#include "protocol/request_id_scanner.h"
#include "server/handshake.h"
#include "server/mesh_service.h"
#include "server/net/filtered_stream.h"

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

/// The open connections, for shutdown and the connection limits, oldest first.
class ConnectionSet {
  public:
    void add(const std::shared_ptr<Closable>& connection);
    void remove(const Closable* connection);
    std::size_t size() const;
    std::vector<std::shared_ptr<Closable>> all() const;
    /// The connection added first among those still open, if any.
    std::shared_ptr<Closable> oldest() const;

  private:
    mutable std::mutex mutex_;
    std::uint64_t next_ = 0;
    std::map<std::uint64_t, std::weak_ptr<Closable>> connections_;  // by order of addition
    std::map<const Closable*, std::uint64_t> order_;
};

/// What connections share.
struct NetContext {
    MeshService& service;
    Logger& logger;
    Metrics& metrics;
    const ServerConfig& config;
    ConnectionSet& websockets;
    ConnectionSet& http_sessions;
    const OriginPolicy& origins;
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
    /// A whole message has been read: hands it to the service.
    void deliver();
    /// From any thread: the output queue has something while the writer was idle.
    void wake();
    void do_write();
    void on_write(beast::error_code ec, std::size_t bytes);
    void do_close(websocket::close_code code);
    void on_close(beast::error_code ec);
    void fail(beast::error_code ec, const char* what);
    void end();

    websocket::stream<FilteredStream> ws_;
    NetContext& context_;
    beast::flat_buffer buffer_;
    // The message being read is over the limit: its bytes are counted and scanned, not kept.
    bool oversized_ = false;
    std::uint64_t oversized_bytes_ = 0;
    protocol::RequestIdScanner id_scanner_;
    std::shared_ptr<Client> client_;
    std::optional<Outgoing> writing_;  // the message in flight
    std::string remote_;
    std::optional<Route> route_;
    bool closing_ = false;  // close once the queue is empty
    bool close_started_ = false;
    bool ended_ = false;
};

}  // namespace isomesh::server::net
