// MeshService's housekeeping thread (mesh_service.h): expiry of idle and orphaned sessions, the
// store's upkeep (activity times, ownership of shared records), splits per second, resource
// metrics, and giving freed memory back to the system.
#include <algorithm>

#include "server/mesh_service.h"
#include "server/resources.h"

namespace isomesh::server {
namespace {

std::chrono::milliseconds to_duration(double seconds) {
    return std::chrono::milliseconds(static_cast<std::int64_t>(seconds * 1000.0));
}

/// How often the time of the last request of each session is stored (idle expiry after a
/// restart, the Redis key's time to live).
Clock::duration activity_interval(const ServerConfig& config) {
    return std::clamp<Clock::duration>(to_duration(config.idle_timeout_s / 4),
                                       std::chrono::milliseconds(100), std::chrono::seconds(60));
}

/// How often a server sharing its store checks that it still owns its live sessions.
constexpr auto kOwnershipInterval = std::chrono::seconds(1);

}  // namespace

void MeshService::expire(Clock::time_point now) {
    std::vector<std::shared_ptr<MeshSession>> expired;
    {
        std::lock_guard lock(sessions_mutex_);
        std::vector<std::map<protocol::SessionId, Entry>::iterator> due;
        for (auto it = sessions_.begin(); it != sessions_.end(); ++it) {
            if (it->second.access != protocol::Access::control) continue;
            const auto& session = it->second.session;
            const auto orphaned = session->orphaned_since();
            const bool orphan_expired =
                orphaned && now - *orphaned >= to_duration(config_.orphan_timeout_s);
            const bool idle_expired =
                now - session->last_request() >= to_duration(config_.idle_timeout_s);
            if (orphan_expired || idle_expired) due.push_back(it);
        }
        for (auto it : due) expired.push_back(retire(it));
    }
    for (const auto& session : expired) {
        persistence_.remove(session->id());
        session->close(protocol::Closed::Reason::expired);
        metrics_.sessions_expired.add();
        logger_.info("session_expired", {{"session", session->serial()}});
    }
}

void MeshService::observe_resources() {
    std::uint64_t estimate = 0, reserved = 0;
    for (const auto& session : live_sessions()) {
        estimate += session->memory_estimate();
        reserved += session->reservation();
    }
    metrics_.memory_estimate_bytes.set(static_cast<std::int64_t>(estimate));
    metrics_.memory_reserved_bytes.set(static_cast<std::int64_t>(reserved));
    metrics_.resident_bytes.set(static_cast<std::int64_t>(resident_bytes()));
}

std::vector<std::shared_ptr<MeshSession>> MeshService::live_sessions() const {
    std::lock_guard lock(sessions_mutex_);
    std::vector<std::shared_ptr<MeshSession>> live;
    for (const auto& [id, entry] : sessions_) {
        if (entry.access == protocol::Access::control) live.push_back(entry.session);
    }
    return live;
}

void MeshService::store_activity() {
    const Clock::time_point now = Clock::now();
    const std::uint64_t now_us = unix_time_us();
    std::vector<store::Activity> touched;
    for (const auto& session : live_sessions()) {
        const Clock::time_point last = session->last_request();
        if (last <= activity_kept_) continue;
        const auto ago = std::chrono::duration_cast<std::chrono::microseconds>(now - last);
        touched.push_back({session->id(), now_us - static_cast<std::uint64_t>(ago.count())});
    }
    activity_kept_ = now;
    persistence_.touch(touched);
}

void MeshService::check_ownership() {
    std::vector<protocol::SessionId> ids;
    for (const auto& session : live_sessions()) ids.push_back(session->id());
    auto owners = persistence_.check(ids);
    if (!owners) return;
    moved(owners->moved);
    for (const protocol::SessionId& id : owners->missing) {
        // The record vanished (the store lost it, or its time to live ran out while the store was
        // down): written again, under the registry's lock so that a close cannot slip between.
        std::lock_guard lock(sessions_mutex_);
        auto it = sessions_.find(id);
        if (it == sessions_.end()) continue;
        const auto& session = it->second.session;
        persistence_.save(session->id(), session->view_id(), session->latest());
    }
}

void MeshService::housekeeping() {
    constexpr auto kTick = std::chrono::milliseconds(100);
    std::uint64_t splits_before = metrics_.splits.value();
    std::uint64_t ended_before = sessions_ended_;
    bool trim_again = false;
    Clock::time_point second_start = Clock::now();
    Clock::time_point activity_start = second_start;
    Clock::time_point ownership_start = second_start;
    std::unique_lock lock(housekeeping_mutex_);
    while (!stopping_) {
        housekeeping_wake_.wait_for(lock, kTick);
        if (stopping_) break;
        const Clock::time_point now = Clock::now();
        expire(now);
        persistence_.maintain(now);
        const bool keep = persistence_.enabled() && persistence_.available() && !shutting_down_;
        if (now - activity_start >= activity_interval(config_)) {
            activity_start = now;
            if (keep) store_activity();
        }
        if (now - ownership_start >= kOwnershipInterval) {
            ownership_start = now;
            if (keep && persistence_.shared()) check_ownership();
        }
        if (now - second_start >= std::chrono::seconds(1)) {
            const std::uint64_t splits = metrics_.splits.value();
            metrics_.splits_per_second.set(static_cast<std::int64_t>(
                static_cast<double>(splits - splits_before) / seconds_between(second_start, now)));
            splits_before = splits;
            second_start = now;
            // Sessions ended: give their memory back to the system (once a second at most), and
            // again a second later: a session's last turn and its connections' queued frames
            // may free their memory after it left the registry.
            if (sessions_ended_ != ended_before || trim_again) {
                trim_again = sessions_ended_ != ended_before;
                ended_before = sessions_ended_;
                release_free_memory();
            }
        }
        observe_resources();
    }
}

}  // namespace isomesh::server
