#include "server/net/websocket_connection.h"

#include <boost/asio/post.hpp>

namespace isomesh::server::net {
namespace {

using namespace std::chrono_literals;

/// Ends of connections that are part of normal life, logged at debug level only.
bool routine(beast::error_code ec) {
    return ec == websocket::error::closed || ec == asio::error::operation_aborted ||
           ec == asio::error::eof || ec == asio::error::connection_reset ||
           ec == asio::error::broken_pipe || ec == beast::error::timeout;
}

}  // namespace

// ---- ConnectionSet ----------------------------------------------------------------------------

void ConnectionSet::add(const std::shared_ptr<Closable>& connection) {
    std::lock_guard lock(mutex_);
    const std::uint64_t order = next_++;
    connections_[order] = connection;
    order_[connection.get()] = order;
}

void ConnectionSet::remove(const Closable* connection) {
    std::lock_guard lock(mutex_);
    auto it = order_.find(connection);
    if (it == order_.end()) return;
    connections_.erase(it->second);
    order_.erase(it);
}

std::shared_ptr<Closable> ConnectionSet::oldest() const {
    std::lock_guard lock(mutex_);
    for (const auto& [order, weak] : connections_) {
        if (auto connection = weak.lock()) return connection;
    }
    return nullptr;
}

std::size_t ConnectionSet::size() const {
    std::lock_guard lock(mutex_);
    return connections_.size();
}

std::vector<std::shared_ptr<Closable>> ConnectionSet::all() const {
    std::lock_guard lock(mutex_);
    std::vector<std::shared_ptr<Closable>> out;
    for (const auto& [key, weak] : connections_) {
        if (auto connection = weak.lock()) out.push_back(std::move(connection));
    }
    return out;
}

// ---- WebSocketConnection ----------------------------------------------------------------------

WebSocketConnection::WebSocketConnection(tcp::socket&& socket, NetContext& context)
    : ws_(std::move(socket)), context_(context) {
    beast::error_code ec;
    auto& tcp_socket = beast::get_lowest_layer(ws_).socket();
    tcp_socket.set_option(tcp::no_delay(true), ec);  // frames are latency-bound, not batched
    const auto endpoint = tcp_socket.remote_endpoint(ec);
    if (!ec) remote_ = endpoint.address().to_string() + ":" + std::to_string(endpoint.port());
}

WebSocketConnection::~WebSocketConnection() {
    context_.websockets.remove(this);
}

void WebSocketConnection::start(http::request<http::string_body> request,
                                std::optional<Route> route) {
    route_ = route;
    beast::get_lowest_layer(ws_).expires_never();  // the WebSocket stream has its own timeouts
    websocket::stream_base::timeout timeouts;
    timeouts.handshake_timeout = 30s;  // also bounds the closing handshake
    timeouts.idle_timeout = 60s;       // a ping after 30 s of silence, closed after 60 s
    timeouts.keep_alive_pings = true;
    ws_.set_option(timeouts);
    ws_.set_option(websocket::stream_base::decorator(
        [](websocket::response_type& response) { response.set(http::field::server, "isomesh"); }));
    ws_.read_message_max(0);  // any size: read in pieces, and beyond the limit not kept (do_read)
    ws_.async_accept(
        request, beast::bind_front_handler(&WebSocketConnection::on_accept, shared_from_this()));
}

void WebSocketConnection::on_accept(beast::error_code ec) {
    if (ec) return fail(ec, "accept");
    std::weak_ptr<WebSocketConnection> weak = shared_from_this();
    client_ = context_.service.connect(
        [weak] {
            if (auto self = weak.lock()) self->wake();
        },
        route_);
    context_.metrics.connections.add(1);
    context_.logger.info("connection_opened", {{"client", client_->id()}, {"remote", remote_}});
    do_read();  // always pending: it completes when the connection ends, whoever ends it
    if (closing_)
        do_close(websocket::close_code::going_away);  // shutdown came during the handshake
}

void WebSocketConnection::do_read() {
    constexpr std::size_t kPiece = 64 * 1024;
    ws_.async_read_some(
        buffer_, kPiece,
        beast::bind_front_handler(&WebSocketConnection::on_read, shared_from_this()));
}

void WebSocketConnection::on_read(beast::error_code ec, std::size_t) {
    if (ec) return fail(ec, "read");
    const auto data = buffer_.cdata();
    const std::string_view piece(static_cast<const char*>(data.data()), data.size());
    if (!oversized_ && buffer_.size() > context_.config.max_message_bytes) {
        oversized_ = true;  // from here on the message is only scanned and counted
        oversized_bytes_ = 0;
        id_scanner_ = {};
    }
    if (oversized_) {
        oversized_bytes_ += piece.size();
        id_scanner_.feed(piece);
        buffer_.consume(buffer_.size());
    }
    if (ws_.is_message_done()) deliver();
    do_read();
}

void WebSocketConnection::deliver() {
    if (oversized_) {
        oversized_ = false;
        if (ws_.got_text()) {
            context_.service.receive_oversized(client_, oversized_bytes_, id_scanner_.id());
        } else {
            context_.service.receive_binary(client_);
        }
        return;
    }
    if (ws_.got_text()) {
        const auto data = buffer_.cdata();
        context_.service.receive(
            client_, std::string_view(static_cast<const char*>(data.data()), data.size()));
    } else {
        context_.service.receive_binary(client_);
    }
    buffer_.consume(buffer_.size());
}

void WebSocketConnection::wake() {
    asio::post(ws_.get_executor(), [self = shared_from_this()] { self->do_write(); });
}

void WebSocketConnection::do_write() {
    if (writing_ || close_started_ || ended_ || !client_) return;
    if (client_->queue().overflowed()) {
        context_.logger.warn(
            "connection_overflowed",
            {{"client", client_->id()}, {"queued_bytes", client_->queue().queued_bytes()}});
        return do_close(websocket::close_code::policy_error);
    }
    writing_ = client_->queue().next();
    if (!writing_) {
        if (closing_) do_close(websocket::close_code::going_away);
        return;
    }
    ws_.binary(writing_->binary());
    const void* data = writing_->binary() ? static_cast<const void*>(writing_->frame->data())
                                          : static_cast<const void*>(writing_->text->data());
    ws_.async_write(asio::buffer(data, writing_->size()),
                    beast::bind_front_handler(&WebSocketConnection::on_write, shared_from_this()));
}

void WebSocketConnection::on_write(beast::error_code ec, std::size_t bytes) {
    if (ec) return fail(ec, "write");
    context_.metrics.bytes_sent.add(bytes);
    if (writing_->binary()) {
        context_.metrics.frame_latency_seconds.observe(
            seconds_between(writing_->created, Clock::now()));
    }
    writing_.reset();
    const auto stalled = client_->queue().written();
    if (!stalled.empty()) context_.service.catch_up(client_, stalled);
    do_write();
}

void WebSocketConnection::do_close(websocket::close_code code) {
    if (close_started_ || ended_) return;
    close_started_ = true;
    ws_.async_close(code,
                    beast::bind_front_handler(&WebSocketConnection::on_close, shared_from_this()));
}

void WebSocketConnection::on_close(beast::error_code ec) {
    // The pending read completes with websocket::error::closed once the peer answers.
    if (ec) fail(ec, "close");
}

void WebSocketConnection::shutdown() {
    asio::post(ws_.get_executor(), [self = shared_from_this()] {
        self->closing_ = true;
        self->do_write();  // closes once the queue is empty
    });
}

void WebSocketConnection::abort() {
    asio::post(ws_.get_executor(), [self = shared_from_this()] {
        beast::error_code ignored;
        beast::get_lowest_layer(self->ws_).socket().close(ignored);
    });
}

void WebSocketConnection::fail(beast::error_code ec, const char* what) {
    if (ended_) return;
    const LogLevel level = routine(ec) ? LogLevel::debug : LogLevel::warn;
    context_.logger.log(
        level, "connection_error",
        {{"client", client_ ? client_->id() : 0}, {"during", what}, {"error", ec.message()}});
    end();
}

void WebSocketConnection::end() {
    if (ended_) return;
    ended_ = true;
    if (!client_) return;
    context_.service.disconnect(client_);
    context_.metrics.connections.add(-1);
    context_.logger.info("connection_closed", {{"client", client_->id()}, {"remote", remote_}});
}

}  // namespace isomesh::server::net
