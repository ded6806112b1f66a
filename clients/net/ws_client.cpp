// The Boost.Beast part of ws_client.h: asynchronous WebSocket connections on an io_context run by
// a few threads (the model is Beast's websocket_client_async example, with one strand per
// connection, our own write queue and at most one write in flight), and a one-shot HTTP GET.
#include "ws_client.h"

#include <deque>
#include <thread>
#include <vector>

#include <boost/asio/connect.hpp>
#include <boost/asio/executor_work_guard.hpp>
#include <boost/asio/io_context.hpp>
#include <boost/asio/ip/tcp.hpp>
#include <boost/asio/post.hpp>
#include <boost/asio/steady_timer.hpp>
#include <boost/asio/strand.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/http.hpp>
#include <boost/beast/websocket.hpp>

namespace isomesh::net {
namespace {

namespace asio = boost::asio;
namespace beast = boost::beast;
namespace http = beast::http;
namespace websocket = beast::websocket;
using tcp = asio::ip::tcp;
using Strand = asio::strand<asio::io_context::executor_type>;

std::string describe(beast::error_code ec, std::string_view during) {
    return std::string(during) + ": " + ec.message();
}

/// Host header value: IPv6 addresses go back into brackets.
std::string host_header(const Url& url) {
    const std::string host =
        url.host.find(':') != std::string::npos ? "[" + url.host + "]" : url.host;
    return host + ":" + url.port;
}

class AsyncConnection final : public WsConnection,
                              public std::enable_shared_from_this<AsyncConnection> {
  public:
    AsyncConnection(asio::io_context& io, Url url, WsHandlers handlers, const WsOptions& options)
        : strand_(asio::make_strand(io)),
          resolver_(strand_),
          ws_(strand_),
          url_(std::move(url)),
          handlers_(std::move(handlers)),
          options_(options) {}

    void start() override {
        beast::get_lowest_layer(ws_).expires_after(options_.connect_timeout);
        resolver_.async_resolve(url_.host, url_.port,
                                beast::bind_front_handler(&AsyncConnection::on_resolve, self()));
    }

    void send_text(std::string text) override {
        asio::post(strand_, [self = self(), text = std::move(text)]() mutable {
            if (self->finished_ || self->closing_) return;
            self->queue_.push_back(std::move(text));
            if (self->open_ && !self->writing_) self->write_next();
        });
    }

    void close() override {
        asio::post(strand_, [self = self()] {
            if (self->finished_ || self->closing_) return;
            self->closing_ = true;
            if (!self->open_) {
                // Still connecting: abandon it; the pending operation fails and finishes us.
                self->resolver_.cancel();
                beast::get_lowest_layer(self->ws_).cancel();
            } else if (!self->writing_) {
                self->close_handshake();
            }
        });
    }

    void after(std::chrono::microseconds delay, std::function<void()> callback) override {
        auto timer = std::make_shared<asio::steady_timer>(strand_, delay);
        timer->async_wait(
            [self = self(), timer, callback = std::move(callback)](beast::error_code ec) {
                if (!ec && !self->finished_) callback();
            });
    }

  private:
    std::shared_ptr<AsyncConnection> self() { return shared_from_this(); }

    void on_resolve(beast::error_code ec, tcp::resolver::results_type results) {
        if (ec) return finish(describe(ec, "resolve " + url_.host));
        beast::get_lowest_layer(ws_).async_connect(
            results, beast::bind_front_handler(&AsyncConnection::on_connect, self()));
    }

    void on_connect(beast::error_code ec, const tcp::endpoint&) {
        if (ec) return finish(describe(ec, "connect to " + host_header(url_)));
        beast::get_lowest_layer(ws_).socket().set_option(tcp::no_delay(true), ec);
        ws_.read_message_max(options_.max_message_bytes);
        ws_.set_option(websocket::stream_base::decorator([](websocket::request_type& request) {
            request.set(http::field::user_agent, "isomesh-client");
        }));
        ws_.async_handshake(host_header(url_), url_.target,
                            beast::bind_front_handler(&AsyncConnection::on_handshake, self()));
    }

    void on_handshake(beast::error_code ec) {
        if (ec) return finish(describe(ec, "WebSocket handshake with " + url_.to_string()));
        // From here on the WebSocket stream's own timeouts apply (closing handshake, pings).
        beast::get_lowest_layer(ws_).expires_never();
        ws_.set_option(websocket::stream_base::timeout::suggested(beast::role_type::client));
        open_ = true;
        if (handlers_.open) handlers_.open();
        if (closing_) return close_handshake();
        if (!queue_.empty()) write_next();
        read_next();
    }

    void read_next() {
        ws_.async_read(buffer_, beast::bind_front_handler(&AsyncConnection::on_read, self()));
    }

    void on_read(beast::error_code ec, std::size_t) {
        if (ec) return finish(clean_end(ec) ? "" : describe(ec, "read"));
        WsMessage message{ws_.got_binary(), beast::buffers_to_string(buffer_.data())};
        buffer_.consume(buffer_.size());
        if (handlers_.message) handlers_.message(std::move(message));
        if (!finished_) read_next();
    }

    void write_next() {
        writing_ = true;
        ws_.text(true);
        ws_.async_write(asio::buffer(queue_.front()),
                        beast::bind_front_handler(&AsyncConnection::on_write, self()));
    }

    void on_write(beast::error_code ec, std::size_t) {
        writing_ = false;
        if (ec) return finish(describe(ec, "write"));
        queue_.pop_front();
        if (!queue_.empty()) return write_next();
        if (closing_) close_handshake();
    }

    /// The server closed, or our closing handshake ended the pending read (Beast aborts it).
    bool clean_end(beast::error_code ec) const {
        return ec == websocket::error::closed || (closing_ && ec == asio::error::operation_aborted);
    }

    void close_handshake() {
        ws_.async_close(websocket::close_code::normal, [self = self()](beast::error_code ec) {
            self->finish(ec ? describe(ec, "close") : "");
        });
    }

    /// Reports the end once and drops the handlers (they may hold the owner of this connection).
    void finish(const std::string& error) {
        if (finished_) return;
        finished_ = true;
        beast::error_code ignored;
        beast::get_lowest_layer(ws_).socket().close(ignored);
        WsHandlers handlers = std::move(handlers_);
        handlers_ = {};
        if (handlers.closed) handlers.closed(closing_ && !open_ ? "" : error);
    }

    Strand strand_;
    tcp::resolver resolver_;
    websocket::stream<beast::tcp_stream> ws_;
    beast::flat_buffer buffer_;
    Url url_;
    WsHandlers handlers_;
    WsOptions options_;
    std::deque<std::string> queue_;
    bool open_ = false;
    bool writing_ = false;
    bool closing_ = false;
    bool finished_ = false;
};

}  // namespace

struct WsEventLoop::Impl {
    asio::io_context io;
    asio::executor_work_guard<asio::io_context::executor_type> work = asio::make_work_guard(io);
    std::vector<std::thread> threads;
};

WsEventLoop::WsEventLoop(unsigned threads) : impl_(std::make_unique<Impl>()) {
    for (unsigned i = 0; i < std::max(threads, 1u); ++i) {
        impl_->threads.emplace_back([io = &impl_->io] { io->run(); });
    }
}

WsEventLoop::~WsEventLoop() {
    stop();
}

void WsEventLoop::stop() {
    impl_->work.reset();
    impl_->io.stop();
    for (std::thread& thread : impl_->threads) {
        if (thread.joinable()) thread.join();
    }
}

std::shared_ptr<WsConnection> WsEventLoop::connection(const Url& url, WsHandlers handlers,
                                                      const WsOptions& options) {
    if (url.scheme != "ws") throw NetError("not a ws:// URL: " + url.to_string());
    return std::make_shared<AsyncConnection>(impl_->io, url, std::move(handlers), options);
}

std::string http_get(const Url& url, std::chrono::milliseconds timeout) {
    if (url.scheme != "http") throw NetError("not an http:// URL: " + url.to_string());
    asio::io_context io;
    tcp::resolver resolver(io);
    beast::tcp_stream stream(io);
    http::response<http::string_body> response;
    beast::error_code failure;
    std::string during;
    auto fail = [&](beast::error_code ec, std::string_view what) {
        failure = ec;
        during = what;
    };
    beast::flat_buffer buffer;
    http::request<http::empty_body> request(http::verb::get, url.target, 11);
    request.set(http::field::host, host_header(url));
    request.set(http::field::user_agent, "isomesh-client");
    stream.expires_after(timeout);  // one deadline for the whole exchange
    resolver.async_resolve(url.host, url.port, [&](beast::error_code ec, auto results) {
        if (ec) return fail(ec, "resolve");
        stream.async_connect(results, [&](beast::error_code ec, const tcp::endpoint&) {
            if (ec) return fail(ec, "connect");
            http::async_write(stream, request, [&](beast::error_code ec, std::size_t) {
                if (ec) return fail(ec, "write");
                http::async_read(stream, buffer, response, [&](beast::error_code ec, std::size_t) {
                    if (ec) fail(ec, "read");
                });
            });
        });
    });
    io.run();
    if (failure) throw NetError("GET " + url.to_string() + ": " + describe(failure, during));
    if (response.result() != http::status::ok) {
        throw NetError("GET " + url.to_string() + ": HTTP " +
                       std::to_string(response.result_int()));
    }
    beast::error_code ignored;
    stream.socket().shutdown(tcp::socket::shutdown_both, ignored);
    return std::move(response.body());
}

}  // namespace isomesh::net
