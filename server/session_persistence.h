// What the service asks of the session store (server/store/): a session's record is written before
// the reply that confirms it leaves (`created`, `updated`), deleted when the session ends (close,
// expiry, failure), and read back to rebuild a session after a restart or on another server.
//
// A record also keeps the session's view id, so that a rebuilt session answers to both its ids.
//
// A definition is enough to rebuild a session: it is the `create` request that makes the session's
// latest version (source, every parameter value, box, constraints in force), and meshes are
// deterministic, so the rebuilt session converges to the mesh a new session with that definition
// converges to.
//
// The store being down is a state, not an error of the server: while it is, calls return at once
// without trying it (requests that need it are refused with store_unavailable), existing sessions
// keep streaming, and maintain() probes it every kProbeInterval until it answers again; deletions
// that could not be made are retried then.
#pragma once

#include <atomic>
#include <memory>
#include <mutex>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "server/clock.h"
#include "server/function_version.h"
#include "server/log.h"
#include "server/metrics.h"
#include "server/store/session_store.h"

namespace isomesh::server {

/// The `create` message (JSON) that makes `version` from scratch.
std::string definition_of(const FunctionVersion& version);

/// The version a stored record describes, compiled and checked like a `create` (a record is
/// refused when the server's limits changed, e.g. a lower --max-triangles).
VersionResult restored_version(const store::SessionRecord& record, const VersionLimits& limits);

class SessionPersistence {
  public:
    static constexpr auto kProbeInterval = std::chrono::milliseconds(500);

    /// `store` may be null (--store none): the service then keeps sessions in memory only.
    SessionPersistence(std::unique_ptr<store::SessionStore> store, Metrics& metrics,
                       Logger& logger);

    bool enabled() const { return store_ != nullptr; }
    /// Several servers share the store (sessions load on demand, ownership is checked).
    bool shared() const { return store_ && store_->shared(); }
    /// False while the store is down.
    bool available() const { return up_; }
    /// This server instance's name in the records it owns (random per process).
    const std::string& owner() const { return owner_; }

    enum class Outcome {
        ok,
        moved,        ///< another server owns the session now
        missing,      ///< there is no record
        unavailable,  ///< the store is down
    };

    /// Writes the record of session `id` (view id `view`) at `version`.
    Outcome save(const protocol::SessionId& id, const protocol::SessionId& view,
                 const FunctionVersion& version);
    /// Deletes the record of an ended session; retried by maintain() while the store is down.
    void remove(const protocol::SessionId& id);

    struct Claimed {
        Outcome outcome = Outcome::missing;
        std::optional<store::SessionRecord> record;  // when ok
    };
    /// True when `id` (a session's id or view id) has a record (false too while the store is
    /// down).
    bool exists(const protocol::SessionId& id);
    /// Takes over the record of `id`, a session's id or view id (this server serves it from now
    /// on).
    Claimed claim(const protocol::SessionId& id);
    /// Every record not idle since before `active_after_us`, taken over (an unshared store at
    /// start); the older ones are deleted.
    std::vector<store::SessionRecord> claim_all(std::uint64_t active_after_us);
    /// Records when sessions were last named by a request (idle expiry after a restart).
    void touch(const std::vector<store::Activity>& activity);

    struct Ownership {
        std::vector<protocol::SessionId> moved;    ///< another server owns them now
        std::vector<protocol::SessionId> missing;  ///< their record is gone
    };
    /// Checks who owns the records of `ids` (sessions live here; none: whether the store answers);
    /// nothing while the store is down.
    std::optional<Ownership> check(const std::vector<protocol::SessionId>& ids);

    /// The housekeeper's turn: probes a store that is down, retries deletions.
    void maintain(Clock::time_point now);

  private:
    /// Runs `call` on the store unless it is down, timing it into `histogram`; a failure marks
    /// the store down. Nothing when it is down or failed.
    template <class T, class Call>
    std::optional<T> attempt(Histogram& histogram, const char* what, Call&& call);
    void failed(const char* what, const std::string& message);
    /// The id of the session whose view id is `view` (nothing inside: none); nothing while the
    /// store is down.
    std::optional<std::optional<protocol::SessionId>> control_of(const protocol::SessionId& view);
    Claimed claim_record(const protocol::SessionId& id);
    void retry_removals();

    std::unique_ptr<store::SessionStore> store_;
    Metrics& metrics_;
    Logger& logger_;
    const std::string owner_;
    std::atomic<bool> up_{true};
    std::mutex mutex_;  // guards what follows
    Clock::time_point next_probe_{};
    std::set<protocol::SessionId> removals_;  // deletions to retry
};

}  // namespace isomesh::server
