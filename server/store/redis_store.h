// The shared session store: Redis (Debian's redis-server, through libhiredis), for several
// servers behind a load balancer (deploy/README.md).
//
// A record is the hash `isomesh:session:<id>` with the fields owner, version, definition,
// created_us and active_us. Each operation is one Lua script (EVAL), so that "write if I own it"
// and "take it and read it" are atomic however many servers race. Every write renews the key's
// time to live (the server's idle timeout and a margin): records of sessions nobody comes back to
// after a crash disappear by themselves.
//
// Durability is Redis's: an acknowledged write is in Redis's memory; with `appendonly yes` (as in
// deploy/redis.conf) it also survives a Redis restart.
//
// One connection, used under a mutex; calls time out after kTimeout (then the call fails and the
// service leaves the store alone until a probe answers). A connection Redis closed is reopened
// once within the call, so a restarted Redis is picked up by the next call.
#pragma once

#include <chrono>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "server/store/session_store.h"

struct redisContext;
struct redisReply;

namespace isomesh::server::store {

class RedisStore final : public SessionStore {
  public:
    static constexpr std::chrono::milliseconds kTimeout{1000};

    /// Connects lazily: a Redis that is down now is tried again on each call.
    RedisStore(std::string host, std::uint16_t port, std::uint32_t ttl_seconds);
    ~RedisStore() override;

    std::string describe() const override;
    bool shared() const override { return true; }
    StoreResult<Status> save(const SessionRecord& record) override;
    StoreResult<Status> remove(const protocol::SessionId& id, std::string_view owner) override;
    StoreResult<Status> touch(std::span<const Activity> activity, std::string_view owner) override;
    StoreResult<std::optional<SessionRecord>> claim(const protocol::SessionId& id,
                                                    std::string_view owner) override;
    /// A shared store loads sessions on demand: nothing is claimed at start.
    StoreResult<std::vector<SessionRecord>> claim_all(std::string_view owner,
                                                      std::uint64_t active_after_us) override;
    StoreResult<std::optional<protocol::SessionId>> control_of(
        const protocol::SessionId& view) override;
    StoreResult<std::vector<std::string>> owners(std::span<const protocol::SessionId> ids) override;
    StoreResult<Status> ping() override;

  private:
    struct ReplyDeleter {
        void operator()(redisReply* reply) const;
    };
    using Reply = std::unique_ptr<redisReply, ReplyDeleter>;

    /// Runs one command (arguments as given), reconnecting once on a broken connection. An
    /// error reply from Redis is a failure too.
    StoreResult<Reply> command(const std::vector<std::string>& arguments);
    /// EVAL of `script` with `keys` and then `arguments`.
    StoreResult<Reply> eval(const char* script, const std::vector<std::string>& keys,
                            const std::vector<std::string>& arguments);
    std::optional<std::string> connect();
    void disconnect();

    const std::string host_;
    const std::uint16_t port_;
    const std::string ttl_;
    std::mutex mutex_;
    redisContext* context_ = nullptr;
};

}  // namespace isomesh::server::store
