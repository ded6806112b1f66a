// WsClient (ws_client.h): a blocking connection made of an asynchronous one on its own I/O thread,
// whose callbacks fill an inbox that read() waits on.
#include <condition_variable>
#include <deque>
#include <mutex>

#include "ws_client.h"

namespace isomesh::net {

struct WsClient::Inbox {
    std::mutex mutex;
    std::condition_variable changed;
    bool open = false;
    std::optional<std::string> ended;  ///< why the connection ended, once it has
    std::deque<WsMessage> messages;

    WsHandlers handlers(const std::shared_ptr<Inbox>& self) {
        WsHandlers h;
        h.open = [self] { self->update([&] { self->open = true; }); };
        h.message = [self](WsMessage&& message) {
            self->update([&] { self->messages.push_back(std::move(message)); });
        };
        h.closed = [self](const std::string& error) {
            self->update([&] { self->ended = error.empty() ? "closed by the server" : error; });
        };
        return h;
    }

    template <class F>
    void update(F&& change) {
        {
            std::lock_guard lock(mutex);
            change();
        }
        changed.notify_all();
    }
};

WsClient::WsClient(const Url& url, const WsOptions& options) : inbox_(std::make_shared<Inbox>()) {
    connection_ = loop_.connection(url, inbox_->handlers(inbox_), options);
    connection_->start();
    std::unique_lock lock(inbox_->mutex);
    // The connection's own timeout bounds this wait.
    inbox_->changed.wait(lock, [&] { return inbox_->open || inbox_->ended; });
    if (!inbox_->open) throw NetError(*inbox_->ended);
}

WsClient::~WsClient() {
    connection_->close();
}

void WsClient::send_text(std::string text) {
    connection_->send_text(std::move(text));
}

std::optional<WsMessage> WsClient::read(std::chrono::steady_clock::time_point deadline) {
    std::unique_lock lock(inbox_->mutex);
    inbox_->changed.wait_until(lock, deadline,
                               [&] { return !inbox_->messages.empty() || inbox_->ended; });
    if (!inbox_->messages.empty()) {
        WsMessage message = std::move(inbox_->messages.front());
        inbox_->messages.pop_front();
        return message;
    }
    if (inbox_->ended) throw NetError(*inbox_->ended);
    return std::nullopt;
}

void WsClient::close(std::chrono::milliseconds timeout) {
    connection_->close();
    std::unique_lock lock(inbox_->mutex);
    inbox_->changed.wait_for(lock, timeout, [&] { return inbox_->ended.has_value(); });
}

}  // namespace isomesh::net
