// The stream under each WebSocket: a beast::tcp_stream whose incoming bytes pass through a
// CloseCodeFilter (server/close_code_filter.h) before Beast parses them, so that an invalid close
// code fails the connection (1002) instead of being echoed. Writes pass through untouched. Shaped
// like beast::flat_stream: next_layer(), the executor, and the teardown customization points.
//
// Included only by the net/*.cpp files: Beast compiles slowly.
#pragma once

#include <algorithm>
#include <array>
#include <cstring>

#include <boost/asio/associated_executor.hpp>
#include <boost/asio/async_result.hpp>
#include <boost/asio/bind_executor.hpp>
#include <boost/asio/buffer.hpp>
#include <boost/asio/post.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/websocket/teardown.hpp>

#include "server/close_code_filter.h"

namespace isomesh::server::net {

class FilteredStream {
  public:
    using executor_type = boost::beast::tcp_stream::executor_type;

    explicit FilteredStream(boost::asio::ip::tcp::socket&& socket) : next_(std::move(socket)) {}

    executor_type get_executor() noexcept { return next_.get_executor(); }
    boost::beast::tcp_stream& next_layer() noexcept { return next_; }
    const boost::beast::tcp_stream& next_layer() const noexcept { return next_; }

    template <class MutableBuffers, class Handler>
    auto async_read_some(const MutableBuffers& buffers, Handler&& handler) {
        return boost::asio::async_initiate<Handler, void(boost::beast::error_code, std::size_t)>(
            [this](auto completion, const MutableBuffers& into) {
                read(boost::asio::buffer(*boost::asio::buffer_sequence_begin(into)),
                     std::move(completion));
            },
            handler, buffers);
    }

    template <class ConstBuffers, class Handler>
    auto async_write_some(const ConstBuffers& buffers, Handler&& handler) {
        return next_.async_write_some(buffers, std::forward<Handler>(handler));
    }

  private:
    /// Completes with bytes the filter released: those left from the last socket read, or those of
    /// a new one (read again when the filter releases nothing, i.e. holds back one byte).
    template <class Completion>
    void read(boost::asio::mutable_buffer into, Completion completion) {
        auto executor = boost::asio::get_associated_executor(completion, get_executor());
        if (released_ > start_ || into.size() == 0) {
            const std::size_t n = deliver(into);
            return boost::asio::post(executor, [n, completion = std::move(completion)]() mutable {
                std::move(completion)(boost::beast::error_code{}, n);
            });
        }
        next_.async_read_some(
            boost::asio::buffer(buffer_.data() + size_, buffer_.size() - size_),
            boost::asio::bind_executor(
                executor, [this, into, completion = std::move(completion)](
                              boost::beast::error_code ec, std::size_t n) mutable {
                    size_ += n;
                    released_ += filter_.filter({buffer_.data() + released_, size_ - released_});
                    if (released_ == start_ && !ec) return read(into, std::move(completion));
                    std::move(completion)(ec, deliver(into));
                }));
    }

    /// Copies released bytes into `into`; returns how many.
    std::size_t deliver(boost::asio::mutable_buffer into) {
        const std::size_t n = std::min(into.size(), released_ - start_);
        std::memcpy(into.data(), buffer_.data() + start_, n);
        start_ += n;
        if (start_ == released_) {  // keep the held-back byte, if any, at the front
            std::memmove(buffer_.data(), buffer_.data() + start_, size_ - start_);
            size_ -= start_;
            released_ = start_ = 0;
        }
        return n;
    }

    boost::beast::tcp_stream next_;
    CloseCodeFilter filter_;
    std::array<std::uint8_t, 16384> buffer_{};
    std::size_t start_ = 0;     // first byte not yet delivered
    std::size_t released_ = 0;  // end of the bytes the filter released
    std::size_t size_ = 0;      // end of the bytes read
};

inline void teardown(boost::beast::role_type role, FilteredStream& stream,
                     boost::beast::error_code& ec) {
    using boost::beast::teardown;
    teardown(role, stream.next_layer(), ec);
}

template <class TeardownHandler>
void async_teardown(boost::beast::role_type role, FilteredStream& stream,
                    TeardownHandler&& handler) {
    using boost::beast::async_teardown;
    async_teardown(role, stream.next_layer(), std::forward<TeardownHandler>(handler));
}

}  // namespace isomesh::server::net
