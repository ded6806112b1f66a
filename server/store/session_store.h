// The session store: where servers keep the definition of every session, so that a restart, a
// crash or another server can rebuild it. Meshes are deterministic, so the definition (the
// `create` request that makes the session's latest version, and the version number) and the
// session's view id are all a session needs; frames are never stored.
//
// One record per session (SessionRecord), found by its id or its view id. Each record names its
// *owner*, the server instance that serves the session: writes and deletes apply only for the
// owner, and a server that loads a session claims it, so that two servers never both accept changes
// to one session (after a failover the old owner's late writes are refused and it learns that the
// session moved).
//
// Implementations: SQLite in WAL mode (sqlite_store.h, one server, the default) and Redis
// (redis_store.h, shared by every server of a cluster). Every call is synchronous, thread-safe and
// bounded in time; a failure is reported (StoreError), never thrown.
#pragma once

#include <cstdint>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "protocol/errors.h"
#include "protocol/messages.h"

namespace isomesh::server::store {

/// What a store keeps of one session.
struct SessionRecord {
    protocol::SessionId id;
    /// The session's read-only view id (PROTOCOL.md 3.2); all zeros in records written before
    /// view ids were kept.
    protocol::SessionId view;
    std::uint32_t version = 1;  ///< the function version the definition makes
    /// The `create` message (JSON text, PROTOCOL.md) that makes the session's latest version:
    /// source, every parameter value supplied so far, box and the constraints in force.
    std::string definition;
    std::string owner;             ///< the server instance serving the session
    std::uint64_t created_us = 0;  ///< Unix time, microseconds
    std::uint64_t active_us = 0;   ///< the last request naming the session (idle expiry)
    friend bool operator==(const SessionRecord&, const SessionRecord&) = default;
};

/// The last activity of a session, for SessionStore::touch.
struct Activity {
    protocol::SessionId id;
    std::uint64_t active_us = 0;
};

/// How a conditional write went.
enum class Status {
    ok,
    not_owner,  ///< another server owns the record: nothing was written
    missing,    ///< there is no such record
};

/// The store did not answer (down, unreachable, timed out, I/O error).
struct StoreError {
    std::string message;
};

template <class T>
using StoreResult = protocol::Result<T, StoreError>;

class SessionStore {
  public:
    virtual ~SessionStore() = default;

    /// "sqlite:PATH" or "redis://HOST:PORT", for logs.
    virtual std::string describe() const = 0;
    /// True when several servers share the store: sessions then load on demand (claim), never
    /// all at start (claim_all).
    virtual bool shared() const = 0;

    /// Writes `record` (a new one, or a new version of one `record.owner` owns; created_us of an
    /// existing record is kept). not_owner when another server owns it.
    virtual StoreResult<Status> save(const SessionRecord& record) = 0;
    /// Deletes the record of `id` if `owner` owns it.
    virtual StoreResult<Status> remove(const protocol::SessionId& id, std::string_view owner) = 0;
    /// Records the activity of sessions `owner` owns (records owned by others are left alone).
    virtual StoreResult<Status> touch(std::span<const Activity> activity,
                                      std::string_view owner) = 0;
    /// Makes `owner` the owner of `id`'s record and returns it; nothing when there is none.
    virtual StoreResult<std::optional<SessionRecord>> claim(const protocol::SessionId& id,
                                                            std::string_view owner) = 0;
    /// Deletes the records idle since before `active_after_us`, then claims and returns all the
    /// others (a server starting on an unshared store).
    virtual StoreResult<std::vector<SessionRecord>> claim_all(std::string_view owner,
                                                              std::uint64_t active_after_us) = 0;
    /// The id of the session whose view id is `view`; nothing when no record has it.
    virtual StoreResult<std::optional<protocol::SessionId>> control_of(
        const protocol::SessionId& view) = 0;
    /// The owner of each of `ids`, in order ("" for a session without a record).
    virtual StoreResult<std::vector<std::string>> owners(
        std::span<const protocol::SessionId> ids) = 0;
    /// Checks that the store answers.
    virtual StoreResult<Status> ping() = 0;
};

/// Where sessions are kept, from `--store`: "none", "sqlite:PATH" or "redis://HOST:PORT".
struct StoreSpec {
    enum class Kind { none, sqlite, redis };
    Kind kind = Kind::none;
    std::string path;  ///< sqlite
    std::string host;  ///< redis
    std::uint16_t port = 6379;
};

/// Parses a --store value; nothing when it is malformed.
std::optional<StoreSpec> parse_store_spec(std::string_view text);

/// Opens the store `spec` names (nullptr for none). A Redis store opens even when Redis is down
/// (it connects on use); `ttl_seconds` is how long Redis keeps a record nobody touches. SQLite
/// failures (no such folder, the file locked by another server) are errors.
StoreResult<std::unique_ptr<SessionStore>> open_store(const StoreSpec& spec,
                                                      std::uint32_t ttl_seconds);

}  // namespace isomesh::server::store
