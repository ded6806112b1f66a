#include "server/store/redis_store.h"

#include <hiredis/hiredis.h>
#include <sys/time.h>

#include <cerrno>
#include <charconv>

namespace isomesh::server::store {
namespace {

// A record is the hash isomesh:session:ID; its view id, when known, also names the key
// isomesh:view:VIEW holding ID, which lives as long as the record. The scripts name that key from
// the record's `view` field (one Redis, not a Redis Cluster).

// KEYS[1] the record, KEYS[2] its view key (absent when the view id is unknown); ARGV owner,
// version, definition, active_us, created_us, ttl, view, id. 1: written; 0: another owner holds it.
constexpr const char* kSave = R"lua(
local owner = redis.call('HGET', KEYS[1], 'owner')
if owner and owner ~= ARGV[1] then return 0 end
redis.call('HSET', KEYS[1], 'owner', ARGV[1], 'version', ARGV[2], 'definition', ARGV[3],
           'active_us', ARGV[4], 'view', ARGV[7])
redis.call('HSETNX', KEYS[1], 'created_us', ARGV[5])
redis.call('EXPIRE', KEYS[1], ARGV[6])
if KEYS[2] then redis.call('SET', KEYS[2], ARGV[8], 'EX', ARGV[6]) end
return 1)lua";

// KEYS[1] the record; ARGV owner. 1: deleted; 0: another owner holds it; -1: no record.
constexpr const char* kRemove = R"lua(
local owner = redis.call('HGET', KEYS[1], 'owner')
if not owner then return -1 end
if owner ~= ARGV[1] then return 0 end
local view = redis.call('HGET', KEYS[1], 'view')
if view and view ~= '' then redis.call('DEL', 'isomesh:view:' .. view) end
redis.call('DEL', KEYS[1])
return 1)lua";

// KEYS the records; ARGV owner, ttl, then one active_us per key.
constexpr const char* kTouch = R"lua(
for i, key in ipairs(KEYS) do
  if redis.call('HGET', key, 'owner') == ARGV[1] then
    redis.call('HSET', key, 'active_us', ARGV[i + 2])
    redis.call('EXPIRE', key, ARGV[2])
    local view = redis.call('HGET', key, 'view')
    if view and view ~= '' then redis.call('EXPIRE', 'isomesh:view:' .. view, ARGV[2]) end
  end
end
return 1)lua";

// KEYS[1] the record; ARGV owner, ttl. The record's fields after taking it, or nil.
constexpr const char* kClaim = R"lua(
if redis.call('EXISTS', KEYS[1]) == 0 then return false end
redis.call('HSET', KEYS[1], 'owner', ARGV[1])
redis.call('EXPIRE', KEYS[1], ARGV[2])
local view = redis.call('HGET', KEYS[1], 'view')
if view and view ~= '' then redis.call('EXPIRE', 'isomesh:view:' .. view, ARGV[2]) end
return redis.call('HMGET', KEYS[1], 'version', 'definition', 'created_us', 'active_us', 'view'))lua";

// KEYS the records. Each one's owner, '' when there is none.
constexpr const char* kOwners = R"lua(
local out = {}
for i, key in ipairs(KEYS) do out[i] = redis.call('HGET', key, 'owner') or '' end
return out)lua";

constexpr std::size_t kBatch = 256;  // keys per script call of touch() and owners()

std::string key(const protocol::SessionId& id) {
    return "isomesh:session:" + id.to_hex();
}

std::string view_key(const protocol::SessionId& view) {
    return "isomesh:view:" + view.to_hex();
}

bool known(const protocol::SessionId& view) {
    return view != protocol::SessionId{};
}

std::string text(const redisReply* reply) {
    if (!reply || (reply->type != REDIS_REPLY_STRING && reply->type != REDIS_REPLY_STATUS))
        return {};
    return std::string(reply->str, reply->len);
}

std::uint64_t number(const redisReply* reply) {
    const std::string digits = text(reply);
    std::uint64_t value = 0;
    std::from_chars(digits.data(), digits.data() + digits.size(), value);
    return value;
}

timeval to_timeval(std::chrono::milliseconds ms) {
    timeval tv{};
    tv.tv_sec = static_cast<time_t>(ms.count() / 1000);
    tv.tv_usec = static_cast<suseconds_t>((ms.count() % 1000) * 1000);
    return tv;
}

}  // namespace

void RedisStore::ReplyDeleter::operator()(redisReply* reply) const {
    freeReplyObject(reply);
}

RedisStore::RedisStore(std::string host, std::uint16_t port, std::uint32_t ttl_seconds)
    : host_(std::move(host)), port_(port), ttl_(std::to_string(ttl_seconds)) {}

RedisStore::~RedisStore() {
    disconnect();
}

std::string RedisStore::describe() const {
    return "redis://" + host_ + ":" + std::to_string(port_);
}

std::optional<std::string> RedisStore::connect() {
    context_ = redisConnectWithTimeout(host_.c_str(), port_, to_timeval(kTimeout));
    if (!context_) return "out of memory";
    if (context_->err) {
        std::string message = context_->errstr;
        disconnect();
        return message;
    }
    redisSetTimeout(context_, to_timeval(kTimeout));
    return std::nullopt;
}

void RedisStore::disconnect() {
    if (context_) redisFree(context_);
    context_ = nullptr;
}

StoreResult<RedisStore::Reply> RedisStore::command(const std::vector<std::string>& arguments) {
    std::vector<const char*> argv;
    std::vector<std::size_t> lengths;
    for (const std::string& argument : arguments) {
        argv.push_back(argument.data());
        lengths.push_back(argument.size());
    }
    std::lock_guard lock(mutex_);
    // A connection opened by an earlier call may have been closed since (Redis restarted): then
    // one more try on a fresh connection. A fresh connection that fails, or a timeout, is final.
    for (bool fresh = context_ == nullptr;; fresh = true) {
        if (!context_) {
            if (auto problem = connect())
                return StoreError{"cannot connect to " + describe() + ": " + *problem};
        }
        Reply reply(static_cast<redisReply*>(redisCommandArgv(
            context_, static_cast<int>(argv.size()), argv.data(), lengths.data())));
        if (reply) {
            if (reply->type == REDIS_REPLY_ERROR)
                return StoreError{describe() + ": " + text(reply.get())};
            return reply;
        }
        const bool closed_by_peer =
            context_->err == REDIS_ERR_EOF || (context_->err == REDIS_ERR_IO && errno != EAGAIN);
        StoreError failure{describe() + ": " + context_->errstr};
        disconnect();
        if (fresh || !closed_by_peer) return failure;
    }
}

StoreResult<RedisStore::Reply> RedisStore::eval(const char* script,
                                                const std::vector<std::string>& keys,
                                                const std::vector<std::string>& arguments) {
    std::vector<std::string> command_line = {"EVAL", script, std::to_string(keys.size())};
    command_line.insert(command_line.end(), keys.begin(), keys.end());
    command_line.insert(command_line.end(), arguments.begin(), arguments.end());
    return command(command_line);
}

StoreResult<Status> RedisStore::save(const SessionRecord& record) {
    std::vector<std::string> keys = {key(record.id)};
    if (known(record.view)) keys.push_back(view_key(record.view));
    auto reply =
        eval(kSave, keys,
             {record.owner, std::to_string(record.version), record.definition,
              std::to_string(record.active_us), std::to_string(record.created_us), ttl_,
              known(record.view) ? record.view.to_hex() : std::string(), record.id.to_hex()});
    if (!reply) return reply.error();
    return reply.value()->integer == 1 ? Status::ok : Status::not_owner;
}

StoreResult<Status> RedisStore::remove(const protocol::SessionId& id, std::string_view owner) {
    auto reply = eval(kRemove, {key(id)}, {std::string(owner)});
    if (!reply) return reply.error();
    switch (reply.value()->integer) {
        case 1:
            return Status::ok;
        case 0:
            return Status::not_owner;
        default:
            return Status::missing;
    }
}

StoreResult<Status> RedisStore::touch(std::span<const Activity> activity, std::string_view owner) {
    for (std::size_t start = 0; start < activity.size(); start += kBatch) {
        std::vector<std::string> keys;
        std::vector<std::string> arguments = {std::string(owner), ttl_};
        for (const Activity& a :
             activity.subspan(start, std::min(kBatch, activity.size() - start))) {
            keys.push_back(key(a.id));
            arguments.push_back(std::to_string(a.active_us));
        }
        auto reply = eval(kTouch, keys, arguments);
        if (!reply) return reply.error();
    }
    return Status::ok;
}

StoreResult<std::optional<SessionRecord>> RedisStore::claim(const protocol::SessionId& id,
                                                            std::string_view owner) {
    auto reply = eval(kClaim, {key(id)}, {std::string(owner), ttl_});
    if (!reply) return reply.error();
    const redisReply* fields = reply.value().get();
    if (fields->type != REDIS_REPLY_ARRAY || fields->elements != 5)
        return std::optional<SessionRecord>();
    SessionRecord record;
    record.id = id;
    record.owner = std::string(owner);
    record.version = static_cast<std::uint32_t>(number(fields->element[0]));
    record.definition = text(fields->element[1]);
    record.created_us = number(fields->element[2]);
    record.active_us = number(fields->element[3]);
    record.view =
        protocol::SessionId::from_hex(text(fields->element[4])).value_or(protocol::SessionId{});
    return std::optional<SessionRecord>(std::move(record));
}

StoreResult<std::optional<protocol::SessionId>> RedisStore::control_of(
    const protocol::SessionId& view) {
    if (!known(view)) return std::optional<protocol::SessionId>();
    auto reply = command({"GET", view_key(view)});
    if (!reply) return reply.error();
    return protocol::SessionId::from_hex(text(reply.value().get()));
}

StoreResult<std::vector<SessionRecord>> RedisStore::claim_all(std::string_view, std::uint64_t) {
    return std::vector<SessionRecord>();
}

StoreResult<std::vector<std::string>> RedisStore::owners(std::span<const protocol::SessionId> ids) {
    std::vector<std::string> out;
    for (std::size_t start = 0; start < ids.size(); start += kBatch) {
        std::vector<std::string> keys;
        for (const auto& id : ids.subspan(start, std::min(kBatch, ids.size() - start)))
            keys.push_back(key(id));
        auto reply = eval(kOwners, keys, {});
        if (!reply) return reply.error();
        const redisReply* list = reply.value().get();
        for (std::size_t i = 0; i < keys.size(); ++i)
            out.push_back(list->type == REDIS_REPLY_ARRAY && i < list->elements
                              ? text(list->element[i])
                              : std::string());
    }
    return out;
}

StoreResult<Status> RedisStore::ping() {
    auto reply = command({"PING"});
    if (!reply) return reply.error();
    return Status::ok;
}

}  // namespace isomesh::server::store
