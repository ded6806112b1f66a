#include "server/session_persistence.h"

#include <random>

namespace isomesh::server {
namespace {

std::string random_owner() {
    std::random_device device;
    char text[17];
    std::snprintf(text, sizeof text, "%08x%08x", device(), device());
    return text;
}

}  // namespace

std::string definition_of(const FunctionVersion& version) {
    protocol::Create create;
    create.source = version.source;
    create.parameters = version.values;
    create.box = version.state.box;
    create.constraints = version.state.constraints;
    return protocol::serialize(protocol::ClientMessage{create});
}

VersionResult restored_version(const store::SessionRecord& record, const VersionLimits& limits) {
    protocol::ParseLimits parse;
    parse.max_message_bytes = parse.max_vm_bytes = 64 << 20;  // accepted once already
    auto parsed = protocol::parse_client_message(record.definition, parse);
    const auto* create = parsed ? std::get_if<protocol::Create>(&parsed.value()) : nullptr;
    if (!create) {
        protocol::ErrorReply error;
        error.code = protocol::ErrorCode::internal;
        error.message = "the stored definition of session " + record.id.to_hex() +
                        " is not a create request" +
                        (parsed ? std::string() : ": " + parsed.error().error.message);
        return error;
    }
    VersionResult version = first_version(*create, limits);
    if (version) version.value().state.version = record.version;
    return version;
}

SessionPersistence::SessionPersistence(std::unique_ptr<store::SessionStore> store, Metrics& metrics,
                                       Logger& logger)
    : store_(std::move(store)), metrics_(metrics), logger_(logger), owner_(random_owner()) {
    metrics_.store_up.set(1);
}

template <class T, class Call>
std::optional<T> SessionPersistence::attempt(Histogram& histogram, const char* what, Call&& call) {
    if (!store_ || !up_) return std::nullopt;
    const Clock::time_point start = Clock::now();
    store::StoreResult<T> result = call(*store_);
    histogram.observe(seconds_between(start, Clock::now()));
    if (!result) {
        failed(what, result.error().message);
        return std::nullopt;
    }
    return std::move(result).value();
}

void SessionPersistence::failed(const char* what, const std::string& message) {
    metrics_.store_errors.add();
    {
        std::lock_guard lock(mutex_);
        next_probe_ = Clock::now() + kProbeInterval;
    }
    if (up_.exchange(false)) {
        metrics_.store_up.set(0);
        logger_.warn("store_down",
                     {{"store", store_->describe()}, {"during", what}, {"message", message}});
    }
}

SessionPersistence::Outcome SessionPersistence::save(const protocol::SessionId& id,
                                                     const protocol::SessionId& view,
                                                     const FunctionVersion& version) {
    if (!store_) return Outcome::ok;
    store::SessionRecord record;
    record.id = id;
    record.view = view;
    record.version = version.state.version;
    record.definition = definition_of(version);
    record.owner = owner_;
    record.created_us = record.active_us = unix_time_us();
    auto saved = attempt<store::Status>(metrics_.store_write_seconds, "save",
                                        [&](store::SessionStore& s) { return s.save(record); });
    if (!saved) return Outcome::unavailable;
    return *saved == store::Status::ok ? Outcome::ok : Outcome::moved;
}

void SessionPersistence::remove(const protocol::SessionId& id) {
    if (!store_) return;
    auto removed =
        attempt<store::Status>(metrics_.store_write_seconds, "remove",
                               [&](store::SessionStore& s) { return s.remove(id, owner_); });
    if (removed) return;  // deleted, or another server's (it moved) or already gone
    std::lock_guard lock(mutex_);
    removals_.insert(id);
}

bool SessionPersistence::exists(const protocol::SessionId& id) {
    auto owners = attempt<std::vector<std::string>>(
        metrics_.store_read_seconds, "owners",
        [&](store::SessionStore& s) { return s.owners(std::span(&id, 1)); });
    if (owners && !owners->empty() && !owners->front().empty()) return true;
    auto control = control_of(id);
    return control && *control;
}

std::optional<std::optional<protocol::SessionId>> SessionPersistence::control_of(
    const protocol::SessionId& view) {
    return attempt<std::optional<protocol::SessionId>>(
        metrics_.store_read_seconds, "control_of",
        [&](store::SessionStore& s) { return s.control_of(view); });
}

SessionPersistence::Claimed SessionPersistence::claim(const protocol::SessionId& id) {
    if (!store_) return {};
    auto claimed = claim_record(id);
    if (claimed.outcome != Outcome::missing) return claimed;
    auto control = control_of(id);  // `id` may be a view id
    if (!control) return {Outcome::unavailable, std::nullopt};
    if (!*control) return claimed;
    return claim_record(**control);
}

SessionPersistence::Claimed SessionPersistence::claim_record(const protocol::SessionId& id) {
    {
        std::lock_guard lock(mutex_);
        if (removals_.contains(id)) return {};  // ended here; its deletion waits for the store
    }
    auto claimed = attempt<std::optional<store::SessionRecord>>(
        metrics_.store_read_seconds, "claim",
        [&](store::SessionStore& s) { return s.claim(id, owner_); });
    if (!claimed) return {Outcome::unavailable, std::nullopt};
    if (!*claimed) return {Outcome::missing, std::nullopt};
    return {Outcome::ok, std::move(*claimed)};
}

std::vector<store::SessionRecord> SessionPersistence::claim_all(std::uint64_t active_after_us) {
    auto records = attempt<std::vector<store::SessionRecord>>(
        metrics_.store_read_seconds, "claim_all",
        [&](store::SessionStore& s) { return s.claim_all(owner_, active_after_us); });
    return records ? std::move(*records) : std::vector<store::SessionRecord>();
}

void SessionPersistence::touch(const std::vector<store::Activity>& activity) {
    if (activity.empty()) return;
    attempt<store::Status>(metrics_.store_write_seconds, "touch",
                           [&](store::SessionStore& s) { return s.touch(activity, owner_); });
}

std::optional<SessionPersistence::Ownership> SessionPersistence::check(
    const std::vector<protocol::SessionId>& ids) {
    if (ids.empty()) {
        // Nothing to check, but a server without sessions must notice the store going down too
        // (/readyz): it asks whether the store answers.
        auto answer = attempt<store::Status>(metrics_.store_read_seconds, "ping",
                                             [](store::SessionStore& s) { return s.ping(); });
        if (!answer) return std::nullopt;
        return Ownership{};
    }
    auto owners =
        attempt<std::vector<std::string>>(metrics_.store_read_seconds, "owners",
                                          [&](store::SessionStore& s) { return s.owners(ids); });
    if (!owners) return std::nullopt;
    Ownership ownership;
    for (std::size_t i = 0; i < ids.size() && i < owners->size(); ++i) {
        const std::string& owner = (*owners)[i];
        if (owner.empty()) {
            ownership.missing.push_back(ids[i]);
        } else if (owner != owner_) {
            ownership.moved.push_back(ids[i]);
        }
    }
    return ownership;
}

void SessionPersistence::maintain(Clock::time_point now) {
    if (!store_) return;
    if (!up_) {
        {
            std::lock_guard lock(mutex_);
            if (now < next_probe_) return;
            next_probe_ = now + kProbeInterval;
        }
        const Clock::time_point start = Clock::now();
        auto answer = store_->ping();
        metrics_.store_read_seconds.observe(seconds_between(start, Clock::now()));
        if (!answer) {
            metrics_.store_errors.add();
            return;
        }
        up_ = true;
        metrics_.store_up.set(1);
        logger_.info("store_up", {{"store", store_->describe()}});
    }
    retry_removals();
}

void SessionPersistence::retry_removals() {
    std::set<protocol::SessionId> pending;
    {
        std::lock_guard lock(mutex_);
        pending.swap(removals_);
    }
    for (const protocol::SessionId& id : pending) remove(id);
}

}  // namespace isomesh::server
