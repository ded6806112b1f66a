#include "server/net/http_server.h"

#include <algorithm>
#include <cerrno>
#include <csignal>
#include <stdexcept>
#include <thread>
#include <vector>

#include <boost/asio/io_context.hpp>
#include <boost/asio/signal_set.hpp>
#include <boost/asio/steady_timer.hpp>
#include <boost/asio/strand.hpp>

#include "server/net/websocket_connection.h"
#include "server/static_files.h"

namespace isomesh::server::net {
namespace {

using namespace std::chrono_literals;
using Response = http::response<http::string_body>;

constexpr std::size_t kMaxHttpBodyBytes = 16 * 1024;  // GET requests carry no body

Response make_response(const http::request<http::string_body>& request, http::status status,
                       std::string body, std::string_view content_type) {
    Response response{status, request.version()};
    response.set(http::field::server, "isomesh");
    response.set(http::field::content_type,
                 beast::string_view(content_type.data(), content_type.size()));
    response.set(http::field::cache_control, "no-cache");
    response.set("X-Content-Type-Options", "nosniff");
    response.keep_alive(request.keep_alive());
    response.body() = std::move(body);
    response.prepare_payload();
    if (request.method() == http::verb::head) response.body().clear();
    return response;
}

Response text_response(const http::request<http::string_body>& request, http::status status,
                       std::string body) {
    return make_response(request, status, std::move(body), "text/plain; charset=utf-8");
}

/// The answer to a request that could not be read: 400 (or 413, 431 for a body or header too
/// large), and the connection closes.
Response malformed_response(beast::error_code ec) {
    http::status status = http::status::bad_request;
    if (ec == http::error::body_limit) status = http::status::payload_too_large;
    if (ec == http::error::header_limit) status = http::status::request_header_fields_too_large;
    http::request<http::string_body> request{http::verb::get, "/", 11};
    request.keep_alive(false);
    return text_response(request, status, "malformed request: " + ec.message() + "\n");
}

/// Ends of an HTTP connection that are no client's mistake: nothing to answer.
bool quiet_end(beast::error_code ec) {
    return ec == http::error::end_of_stream || ec == asio::error::eof ||
           ec == beast::error::timeout || ec == asio::error::operation_aborted ||
           ec == asio::error::connection_reset || ec == asio::error::broken_pipe ||
           ec == asio::error::bad_descriptor || ec == http::error::partial_message;
}

std::optional<std::string_view> header(const http::request<http::string_body>& request,
                                       http::field field) {
    auto it = request.find(field);
    if (it == request.end()) return std::nullopt;
    return std::string_view(it->value().data(), it->value().size());
}

/// One HTTP connection: requests answered one at a time until it closes or upgrades.
class HttpSession final : public Closable, public std::enable_shared_from_this<HttpSession> {
  public:
    HttpSession(tcp::socket&& socket, NetContext& context)
        : stream_(std::move(socket)), context_(context) {
        context_.metrics.http_connections.add(1);
    }
    ~HttpSession() override {
        context_.http_sessions.remove(this);
        context_.metrics.http_connections.add(-1);
    }

    void start() {
        asio::dispatch(stream_.get_executor(),
                       beast::bind_front_handler(&HttpSession::do_read, shared_from_this()));
    }

    void shutdown() override { abort(); }  // responses are small: nothing worth draining

    void abort() override {
        asio::post(stream_.get_executor(), [self = shared_from_this()] {
            beast::error_code ignored;
            self->stream_.socket().shutdown(tcp::socket::shutdown_both, ignored);
            self->stream_.socket().close(ignored);
        });
    }

  private:
    void do_read() {
        parser_.emplace();
        parser_->body_limit(kMaxHttpBodyBytes);
        stream_.expires_after(30s);
        http::async_read(stream_, buffer_, *parser_,
                         beast::bind_front_handler(&HttpSession::on_read, shared_from_this()));
    }

    void on_read(beast::error_code ec, std::size_t) {
        if (ec) {
            if (quiet_end(ec)) return close();
            context_.metrics.http_bad_requests.add();
            return send(malformed_response(ec));
        }
        if (context_.service.shutting_down()) parser_->get().keep_alive(false);
        if (websocket::is_upgrade(parser_->get())) return upgrade();
        context_.metrics.http_requests.add();
        send(handle(parser_->get()));
    }

    void upgrade() {
        const auto& request = parser_->get();
        const std::string_view target(request.target().data(), request.target().size());
        if (target.substr(0, target.find('?')) != "/ws") {
            return send(text_response(request, http::status::not_found, "no WebSocket here\n"));
        }
        auto route = route_of_target(target);
        if (!route) {
            context_.metrics.http_bad_requests.add();
            return send(text_response(request, http::status::bad_request, route.error() + "\n"));
        }
        if (context_.service.shutting_down()) {
            return send(text_response(request, http::status::service_unavailable, "draining\n"));
        }
        UpgradeRequest upgrade;
        upgrade.method =
            std::string_view(request.method_string().data(), request.method_string().size());
        upgrade.version = request.version();
        upgrade.host = header(request, http::field::host).value_or("");
        upgrade.key = header(request, http::field::sec_websocket_key).value_or("");
        upgrade.ws_version = header(request, http::field::sec_websocket_version).value_or("");
        upgrade.origin = header(request, http::field::origin);
        if (auto refusal = check_upgrade(upgrade, context_.origins)) return refuse(*refusal);
        if (context_.websockets.size() >= context_.config.max_connections) {
            return send(text_response(request, http::status::service_unavailable,
                                      "too many connections\n"));
        }
        auto connection = std::make_shared<WebSocketConnection>(stream_.release_socket(), context_);
        context_.websockets.add(connection);
        connection->start(parser_->release(), route.value());
    }

    void refuse(const HandshakeRefusal& refusal) {
        auto& request = parser_->get();
        request.keep_alive(false);
        (refusal.status == 403 ? context_.metrics.origins_refused
                               : context_.metrics.http_bad_requests)
            .add();
        Response response = text_response(request, static_cast<http::status>(refusal.status),
                                          refusal.message + "\n");
        if (refusal.status == 426) response.set(http::field::sec_websocket_version, "13");
        send(std::move(response));
    }

    Response handle(const http::request<http::string_body>& request) {
        if (request.method() != http::verb::get && request.method() != http::verb::head) {
            Response response =
                text_response(request, http::status::method_not_allowed, "GET or HEAD only\n");
            response.set(http::field::allow, "GET, HEAD");
            return response;
        }
        const std::string_view target(request.target().data(), request.target().size());
        const std::string_view path = target.substr(0, target.find('?'));
        if (!target.starts_with('/')) {
            context_.metrics.http_bad_requests.add();
            return text_response(request, http::status::bad_request, "bad request target\n");
        }
        if (path == "/healthz") {
            if (context_.service.shutting_down())
                return text_response(request, http::status::service_unavailable, "draining\n");
            return text_response(request, http::status::ok, "ok\n");
        }
        if (path == "/readyz") {
            if (auto reason = context_.service.unready())
                return text_response(request, http::status::service_unavailable, *reason + "\n");
            return text_response(request, http::status::ok, "ready\n");
        }
        if (path == "/metrics") {
            return make_response(request, http::status::ok, context_.metrics.render(),
                                 "text/plain; version=0.0.4; charset=utf-8");
        }
        if (path == "/ws") {
            return text_response(request, http::status::upgrade_required,
                                 "WebSocket endpoint: connect with a WebSocket client\n");
        }
        FileResult file = load_static_file(context_.config.web_root, target);
        switch (file.status) {
            case FileLookup::found:
                return make_response(request, http::status::ok, std::move(file.file.body),
                                     file.file.content_type);
            case FileLookup::forbidden:
                return text_response(request, http::status::forbidden, "forbidden\n");
            case FileLookup::not_found:
                break;
        }
        return text_response(request, http::status::not_found, "not found\n");
    }

    void send(Response response) {
        auto message = std::make_shared<Response>(std::move(response));
        http::async_write(stream_, *message,
                          [self = shared_from_this(), message](beast::error_code ec, std::size_t) {
                              if (ec || message->need_eof()) return self->close();
                              self->do_read();
                          });
    }

    void close() {
        beast::error_code ignored;
        stream_.socket().shutdown(tcp::socket::shutdown_send, ignored);
    }

    beast::tcp_stream stream_;
    NetContext& context_;
    beast::flat_buffer buffer_;
    std::optional<http::request_parser<http::string_body>> parser_;
};

}  // namespace

struct HttpServer::Impl {
    Impl(MeshService& service, const ServerConfig& config, Logger& logger, Metrics& metrics)
        : origins(config.allow_origin),
          context{service, logger, metrics, config, websockets, http_sessions, origins},
          ioc(static_cast<int>(config.io_threads)),
          acceptor(asio::make_strand(ioc)),
          signals(ioc, SIGINT, SIGTERM, SIGHUP),
          accept_timer(acceptor.get_executor()),
          drain_timer(ioc) {}

    void do_accept() {
        acceptor.async_accept(
            asio::make_strand(ioc),
            [this](beast::error_code ec, tcp::socket socket) { on_accept(ec, std::move(socket)); });
    }

    void on_accept(beast::error_code ec, tcp::socket socket) {
        if (ec == asio::error::operation_aborted || !acceptor.is_open()) return;
        if (ec) return accept_failed(ec);
        accept_backoff = std::chrono::milliseconds(0);
        // Beyond the limit, the oldest HTTP connection makes room (an idle keep-alive, or one
        // that never sent a request): plain connections cannot crowd out the next request.
        if (http_sessions.size() >= context.config.max_http_connections) evict_oldest();
        auto session = std::make_shared<HttpSession>(std::move(socket), context);
        http_sessions.add(session);
        session->start();
        do_accept();
    }

    /// accept() failed: out of file descriptors (EMFILE, ENFILE) or another error. Closes the
    /// oldest HTTP connection to free a descriptor when there is one, and tries again after a
    /// pause that doubles up to a second, logging at most once a second: no busy loop.
    void accept_failed(beast::error_code ec) {
        context.metrics.accept_errors.add();
        ++accept_errors_unlogged;
        const auto now = Clock::now();
        if (now - last_accept_log >= std::chrono::seconds(1)) {
            context.logger.warn("accept_failed", {{"error", ec.message()},
                                                  {"failures", accept_errors_unlogged},
                                                  {"http_connections", http_sessions.size()},
                                                  {"websockets", websockets.size()}});
            accept_errors_unlogged = 0;
            last_accept_log = now;
        }
        const bool out_of_descriptors = ec == asio::error::no_descriptors || ec.value() == ENFILE;
        const bool evicted = out_of_descriptors && evict_oldest();
        accept_backoff = evicted ? std::chrono::milliseconds(10)
                                 : std::clamp(2 * accept_backoff, std::chrono::milliseconds(50),
                                              std::chrono::milliseconds(1000));
        accept_timer.expires_after(accept_backoff);
        accept_timer.async_wait([this](beast::error_code wait_error) {
            if (!wait_error && acceptor.is_open()) do_accept();
        });
    }

    bool evict_oldest() {
        auto oldest = http_sessions.oldest();
        if (!oldest) return false;
        http_sessions.remove(oldest.get());
        oldest->abort();
        context.metrics.http_evicted.add();
        return true;
    }

    void on_signal(beast::error_code ec, int signal) {
        if (ec || draining) return;
        draining = true;
        context.logger.info("draining", {{"signal", signal}});
        // The acceptor stays open while draining, so /healthz answers 503 "draining".
        context.service.shutdown();  // every session cancelled, `closed` queued at once
        for (const auto& connection : websockets.all()) connection->shutdown();
        for (const auto& connection : http_sessions.all()) connection->shutdown();
        drain_deadline = Clock::now() + std::chrono::milliseconds(static_cast<std::int64_t>(
                                            context.config.drain_timeout_s * 1000));
        wait_drained();
    }

    /// Polls until every WebSocket is gone; past the deadline, closes the stragglers' sockets.
    void wait_drained() {
        const auto now = Clock::now();
        if (websockets.size() == 0 || now >= drain_deadline + 500ms) {
            if (websockets.size() > 0)
                context.logger.warn("drain_incomplete", {{"connections", websockets.size()}});
            return stop();
        }
        if (now >= drain_deadline) {
            for (const auto& connection : websockets.all()) connection->abort();
        }
        drain_timer.expires_after(20ms);
        drain_timer.async_wait([this](beast::error_code wait_error) {
            if (!wait_error) wait_drained();
        });
    }

    /// Stops accepting and closes what is left; run() then returns.
    void stop() {
        context.logger.info("drained");
        asio::post(acceptor.get_executor(), [this] {
            beast::error_code ignored;
            acceptor.close(ignored);
            accept_timer.cancel();
        });
        for (const auto& connection : http_sessions.all()) connection->abort();
        for (const auto& connection : websockets.all()) connection->abort();
        ioc.stop();
    }

    // What connections refer to comes first: it outlives the io_context, whose destruction
    // destroys the handlers that still hold connections.
    ConnectionSet websockets;
    ConnectionSet http_sessions;
    OriginPolicy origins;
    NetContext context;
    asio::io_context ioc;
    tcp::acceptor acceptor;
    asio::signal_set signals;
    asio::steady_timer accept_timer;
    asio::steady_timer drain_timer;
    bool draining = false;
    Clock::time_point drain_deadline = Clock::time_point::max();
    std::chrono::milliseconds accept_backoff{0};
    Clock::time_point last_accept_log{};
    std::uint64_t accept_errors_unlogged = 0;
};

HttpServer::HttpServer(MeshService& service, const ServerConfig& config, Logger& logger,
                       Metrics& metrics)
    : impl_(std::make_unique<Impl>(service, config, logger, metrics)) {}

HttpServer::~HttpServer() = default;

std::uint16_t HttpServer::listen() {
    const ServerConfig& config = impl_->context.config;
    beast::error_code ec;
    const auto address = asio::ip::make_address(config.bind_address, ec);
    if (ec) throw std::runtime_error("bad --bind address '" + config.bind_address + "'");
    const tcp::endpoint endpoint(address, config.port);
    auto& acceptor = impl_->acceptor;
    auto check = [&](const char* what) {
        if (ec) throw std::runtime_error(std::string(what) + ": " + ec.message());
    };
    acceptor.open(endpoint.protocol(), ec);
    check("open");
    acceptor.set_option(asio::socket_base::reuse_address(true), ec);
    check("reuse_address");
    acceptor.bind(endpoint, ec);
    check("bind");
    acceptor.listen(asio::socket_base::max_listen_connections, ec);
    check("listen");
    return acceptor.local_endpoint().port();
}

Clock::time_point HttpServer::drain_deadline() const {
    return impl_->drain_deadline;
}

void HttpServer::run() {
    impl_->do_accept();
    impl_->signals.async_wait(
        [this](beast::error_code ec, int signal) { impl_->on_signal(ec, signal); });
    std::vector<std::thread> threads;
    for (unsigned i = 1; i < impl_->context.config.io_threads; ++i)
        threads.emplace_back([this] { impl_->ioc.run(); });
    impl_->ioc.run();
    for (std::thread& thread : threads) thread.join();
}

}  // namespace isomesh::server::net
