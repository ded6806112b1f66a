#include "virtual_user.h"

#include <cmath>
#include <variant>

#include "protocol/frame.h"

namespace isomesh::load {
namespace {

using namespace std::chrono;

/// Slider updates move the parameter by this fraction of its range.
constexpr double kSliderStep = 1.0 / 20;

double ms_since(steady_clock::time_point start) {
    return duration<double, std::milli>(steady_clock::now() - start).count();
}

std::uint64_t system_now_us() {
    return static_cast<std::uint64_t>(
        duration_cast<microseconds>(system_clock::now().time_since_epoch()).count());
}

}  // namespace

VirtualUser::VirtualUser(const Mix& mix, std::size_t index, std::size_t users,
                         UserSettings settings, std::function<void()> on_finished)
    : mix_(mix),
      index_(index),
      users_(users),
      settings_(settings),
      on_finished_(std::move(on_finished)) {}

void VirtualUser::start(net::WsEventLoop& loop, const net::Url& url) {
    auto self = shared_from_this();
    net::WsHandlers handlers;
    handlers.open = [self] { self->create_session(); };
    handlers.message = [self](net::WsMessage&& message) {
        self->stats_.bytes_received += message.data.size();
        if (message.binary) {
            self->on_frame(message);
        } else {
            self->on_text(message.data);
        }
    };
    handlers.closed = [self](const std::string& error) { self->on_closed(error); };
    connection_ = loop.connection(url, std::move(handlers));
    connection_->start();
}

void VirtualUser::stop() {
    connection_->after(microseconds(0), [self = shared_from_this()] {
        self->stopping_ = true;
        if (self->session_) self->send(protocol::Close{std::nullopt, *self->session_});
        self->connection_->close();
    });
}

void VirtualUser::send(const protocol::ClientMessage& message) {
    connection_->send_text(protocol::serialize(message, settings_.protocol_version));
}

void VirtualUser::create_session() {
    if (stopping_) return;
    entry_ = mix_entry(mix_, index_, users_, round_);
    if (settings_.jitter > 0)
        entry_ = jittered(entry_, settings_.jitter, (std::uint64_t{index_} << 32) ^ round_);
    protocol::Create create = entry().create;
    create_id_ = next_request_id_++;
    create.id = create_id_;
    session_.reset();
    replica_ = protocol::MeshReplica();
    have_first_mesh_ = false;
    updates_in_flight_.clear();
    versions_awaited_.clear();
    create_sent_ = steady_clock::now();
    send(create);
}

void VirtualUser::on_text(const std::string& text) {
    auto parsed = protocol::parse_server_message(text);
    if (!parsed) {
        ++stats_.decode_errors;
        stats_.record_error("unreadable message: " + parsed.error().message);
        return;
    }
    std::visit(
        [&](const auto& message) {
            using T = std::decay_t<decltype(message)>;
            if constexpr (std::is_same_v<T, protocol::Created>) {
                if (message.id == protocol::RequestId{create_id_}) {
                    session_ = message.session;
                    ++stats_.sessions_created;
                    stats_.created_ms.push_back(ms_since(create_sent_));
                }
            } else if constexpr (std::is_same_v<T, protocol::Updated>) {
                const auto* id = message.id ? std::get_if<std::int64_t>(&*message.id) : nullptr;
                auto sent = id ? updates_in_flight_.find(*id) : updates_in_flight_.end();
                if (sent == updates_in_flight_.end()) return;
                versions_awaited_[message.state.version] = sent->second;
                updates_in_flight_.erase(sent);
            } else if constexpr (std::is_same_v<T, protocol::Converged>) {
                if (message.session == session_) on_converged(message);
            } else if constexpr (std::is_same_v<T, protocol::ErrorReply>) {
                on_error(message);
            } else if constexpr (std::is_same_v<T, protocol::Closed>) {
                if (message.session == session_ && !stopping_ &&
                    message.reason != protocol::Closed::Reason::closed) {
                    ++stats_.connection_errors;
                    stats_.record_error("session closed by the server");
                }
            }
        },
        parsed.value());
}

void VirtualUser::on_frame(const net::WsMessage& message) {
    const std::uint64_t now_us = system_now_us();
    auto read = protocol::read_frame_header(message.bytes());
    if (!read) {
        ++stats_.decode_errors;
        stats_.record_error("undecodable frame: " + read.error().message);
        return;
    }
    const protocol::FrameHeader& header = read.value();
    if (header.session != session_) return;  // a frame of a session this user has closed
    ++stats_.frames;
    ++(header.kind == protocol::FrameKind::keyframe ? stats_.keyframes : stats_.deltas);
    stats_.triangles_received += header.triangle_count;
    stats_.frame_latency_ms.push_back(
        (static_cast<double>(now_us) - static_cast<double>(header.timestamp_us)) / 1000.0);

    // Either version: a version-2 delta is decoded against the replica's mesh.
    const auto outcome = replica_.receive(message.bytes());
    if (!outcome) {
        ++stats_.decode_errors;
        stats_.record_error("undecodable frame: " + outcome.error().message);
        return;
    }
    if (outcome.value() == protocol::MeshReplica::Outcome::gap ||
        outcome.value() == protocol::MeshReplica::Outcome::inconsistent) {
        ++stats_.resyncs;
        send(protocol::Resync{std::nullopt, header.session});
    }
    if (!have_first_mesh_ && header.kind == protocol::FrameKind::keyframe) {
        stats_.first_mesh_delivery_ms.push_back(stats_.frame_latency_ms.back());
        on_first_mesh();
    }
    // Every update answered by now has its first frame: this one or an earlier one.
    while (!versions_awaited_.empty() &&
           versions_awaited_.begin()->first <= header.function_version) {
        stats_.update_latency_ms.push_back(ms_since(versions_awaited_.begin()->second));
        versions_awaited_.erase(versions_awaited_.begin());
    }
}

void VirtualUser::on_first_mesh() {
    have_first_mesh_ = true;
    const double ms = ms_since(create_sent_);
    stats_.first_mesh_ms.push_back(ms);
    stats_.first_mesh_ms_by_entry[entry().name].push_back(ms);
    if (const auto& slider = entry().slider; slider && settings_.updates_per_s > 0) {
        slider_value_ = entry().create.parameters.at(slider->parameter);
        slider_step_ = kSliderStep * (slider->max - slider->min);
        schedule_update();
    }
}

void VirtualUser::schedule_update() {
    const auto period = duration<double>(1.0 / settings_.updates_per_s);
    connection_->after(duration_cast<microseconds>(period), [self = shared_from_this()] {
        if (self->stopping_ || !self->session_) return;
        self->send_update();
        self->schedule_update();
    });
}

void VirtualUser::send_update() {
    const Slider& slider = *entry().slider;
    if (slider_value_ + slider_step_ > slider.max || slider_value_ + slider_step_ < slider.min) {
        slider_step_ = -slider_step_;
    }
    slider_value_ = std::clamp(slider_value_ + slider_step_, slider.min, slider.max);
    protocol::Update update;
    update.id = next_request_id_++;
    update.session = *session_;
    update.parameters = protocol::Parameters{{slider.parameter, slider_value_}};
    updates_in_flight_[std::get<std::int64_t>(*update.id)] = steady_clock::now();
    ++stats_.updates_sent;
    send(update);
}

void VirtualUser::on_converged(const protocol::Converged& converged) {
    ++stats_.converged;
    if (converged.version == 1 && !entry().slider && settings_.hold_s > 0) recreate_later();
}

void VirtualUser::recreate_later() {
    const auto hold = duration_cast<microseconds>(duration<double>(settings_.hold_s));
    connection_->after(hold, [self = shared_from_this()] {
        if (self->stopping_ || !self->session_) return;
        self->send(protocol::Close{std::nullopt, *self->session_});
        ++self->round_;
        self->create_session();
    });
}

void VirtualUser::on_error(const protocol::ErrorReply& error) {
    ++stats_.server_errors[std::string(protocol::to_string(error.code))];
    stats_.record_error(std::string(protocol::to_string(error.code)) + ": " + error.message + " (" +
                        entry().name + ")");
}

void VirtualUser::on_closed(const std::string& error) {
    if (!stopping_ || !error.empty()) {
        ++stats_.connection_errors;
        stats_.record_error(error.empty() ? "connection closed by the server" : error);
    }
    if (on_finished_) on_finished_();
}

}  // namespace isomesh::load
