// WebSocket and HTTP clients for the C++ clients of the isomesh server (the CLI's `--server`, the
// load generator): plain `ws://` and `http://` over TCP, on Boost.Beast. Beast compiles slowly, so
// it lives in one translation unit (ws_client.cpp) behind these Boost-free declarations.
//
// Two ways to use a connection:
// - WsEventLoop + WsConnection: asynchronous, many connections on a few I/O threads; each
//   connection's callbacks run one at a time, in order, on its own strand;
// - WsClient: one blocking connection (send, then read with a deadline).
#pragma once

#include <chrono>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <span>
#include <stdexcept>
#include <string>
#include <string_view>

namespace isomesh::net {

/// A failed connection, request or read.
class NetError : public std::runtime_error {
  public:
    using std::runtime_error::runtime_error;
};

/// Where to connect: `ws://HOST:PORT/PATH` or `http://HOST:PORT/PATH`.
struct Url {
    std::string scheme;  ///< "ws" or "http"
    std::string host;    ///< a name or an address; IPv6 without its brackets
    std::string port;    ///< "80" when the URL names none
    std::string target;  ///< the path and query, "/" when the URL names none
    /// The URL of `target` on the same host and port (e.g. /metrics next to /ws) with `scheme`.
    Url with(std::string_view scheme, std::string_view target) const;
    std::string to_string() const;
};

/// Parses `ws://` and `http://` URLs (no user info, no fragment; `wss` and `https` are not
/// supported). Throws NetError saying what is wrong.
Url parse_url(std::string_view text);

struct WsMessage {
    bool binary = false;
    std::string data;
    std::span<const std::uint8_t> bytes() const {
        return {reinterpret_cast<const std::uint8_t*>(data.data()), data.size()};
    }
};

/// What a connection reports. Each callback may be empty.
struct WsHandlers {
    std::function<void()> open;  ///< the handshake is done
    std::function<void(WsMessage&&)> message;
    /// Called exactly once, last: `error` is empty after a clean close (either side) and says
    /// what happened otherwise (connection refused, reset, timeout, ...).
    std::function<void(const std::string& error)> closed;
};

struct WsOptions {
    std::chrono::milliseconds connect_timeout{5000};  ///< resolve + TCP connect + handshake
    std::size_t max_message_bytes = 256u << 20;       ///< larger incoming messages fail the read
};

/// An asynchronous WebSocket connection. Every member is thread-safe; handlers and `after`
/// callbacks of one connection never run concurrently.
class WsConnection {
  public:
    virtual ~WsConnection() = default;
    /// Starts connecting; call once. From here on the handlers may run (on an I/O thread), so
    /// store the connection where they can see it first.
    virtual void start() = 0;
    /// Queues a text message; messages sent before the handshake completes wait for it.
    virtual void send_text(std::string text) = 0;
    /// Starts the closing handshake after the queued messages (or abandons a connection still
    /// being opened); `closed` follows.
    virtual void close() = 0;
    /// Runs `callback` on this connection's strand after `delay`, unless the connection has
    /// ended by then.
    virtual void after(std::chrono::microseconds delay, std::function<void()> callback) = 0;
};

/// I/O threads for asynchronous connections. Precondition for destruction: nobody holds a
/// WsConnection of this loop any more; after stop() they may be dropped from any thread.
class WsEventLoop {
  public:
    explicit WsEventLoop(unsigned threads);
    /// stop(), then drops the work still pending.
    ~WsEventLoop();
    WsEventLoop(const WsEventLoop&) = delete;
    WsEventLoop& operator=(const WsEventLoop&) = delete;

    /// Stops the I/O threads and waits for them: no callback runs once it returns. Idempotent.
    void stop();

    /// A connection to `url` (scheme ws), not started yet. Failures, once started, are reported
    /// through `handlers.closed`.
    std::shared_ptr<WsConnection> connection(const Url& url, WsHandlers handlers,
                                             const WsOptions& options = {});

  private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
};

/// One blocking WebSocket connection, for a command-line client.
class WsClient {
  public:
    /// Connects; throws NetError when the connection or the handshake fails.
    explicit WsClient(const Url& url, const WsOptions& options = {});
    ~WsClient();
    WsClient(const WsClient&) = delete;
    WsClient& operator=(const WsClient&) = delete;

    void send_text(std::string text);
    /// The next message, or nothing when none arrived before `deadline`. Throws NetError once the
    /// connection has ended (with the reason, "closed by the server" for a clean close).
    std::optional<WsMessage> read(std::chrono::steady_clock::time_point deadline);
    /// Closes cleanly, waiting at most `timeout` for the server's answer.
    void close(std::chrono::milliseconds timeout = std::chrono::milliseconds(2000));

  private:
    struct Inbox;
    std::shared_ptr<Inbox> inbox_;
    WsEventLoop loop_{1};
    std::shared_ptr<WsConnection> connection_;
};

/// HTTP/1.1 GET of `url` (scheme http); the body of a 200 response. Throws NetError on a failure
/// or another status.
std::string http_get(const Url& url,
                     std::chrono::milliseconds timeout = std::chrono::milliseconds(5000));

}  // namespace isomesh::net
