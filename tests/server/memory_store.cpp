#include "memory_store.h"

namespace isomesh::server::testing {

using store::Status;
using store::StoreError;
using store::StoreResult;

std::optional<StoreError> MemoryStore::failure() const {
    if (down) return StoreError{"memory store: down"};
    return std::nullopt;
}

std::optional<store::SessionRecord> MemoryStore::find(const protocol::SessionId& id) const {
    std::lock_guard lock(mutex_);
    auto it = records_.find(id);
    if (it == records_.end()) return std::nullopt;
    return it->second;
}

std::size_t MemoryStore::size() const {
    std::lock_guard lock(mutex_);
    return records_.size();
}

StoreResult<Status> MemoryStore::save(const store::SessionRecord& record) {
    if (auto f = failure()) return *f;
    std::lock_guard lock(mutex_);
    auto it = records_.find(record.id);
    if (it == records_.end()) {
        records_[record.id] = record;
        return Status::ok;
    }
    if (it->second.owner != record.owner) return Status::not_owner;
    const std::uint64_t created = it->second.created_us;
    it->second = record;
    it->second.created_us = created;
    return Status::ok;
}

StoreResult<Status> MemoryStore::remove(const protocol::SessionId& id, std::string_view owner) {
    if (auto f = failure()) return *f;
    std::lock_guard lock(mutex_);
    auto it = records_.find(id);
    if (it == records_.end()) return Status::missing;
    if (it->second.owner != owner) return Status::not_owner;
    records_.erase(it);
    return Status::ok;
}

StoreResult<Status> MemoryStore::touch(std::span<const store::Activity> activity,
                                       std::string_view owner) {
    if (auto f = failure()) return *f;
    std::lock_guard lock(mutex_);
    for (const auto& a : activity) {
        auto it = records_.find(a.id);
        if (it != records_.end() && it->second.owner == owner) it->second.active_us = a.active_us;
    }
    return Status::ok;
}

StoreResult<std::optional<store::SessionRecord>> MemoryStore::claim(const protocol::SessionId& id,
                                                                    std::string_view owner) {
    if (auto f = failure()) return *f;
    std::lock_guard lock(mutex_);
    auto it = records_.find(id);
    if (it == records_.end()) return std::optional<store::SessionRecord>();
    it->second.owner = std::string(owner);
    return std::optional<store::SessionRecord>(it->second);
}

StoreResult<std::vector<store::SessionRecord>> MemoryStore::claim_all(
    std::string_view owner, std::uint64_t active_after_us) {
    if (auto f = failure()) return *f;
    std::lock_guard lock(mutex_);
    std::vector<store::SessionRecord> out;
    for (auto it = records_.begin(); it != records_.end();) {
        if (it->second.active_us < active_after_us) {
            it = records_.erase(it);
            continue;
        }
        it->second.owner = std::string(owner);
        out.push_back(it->second);
        ++it;
    }
    return out;
}

StoreResult<std::optional<protocol::SessionId>> MemoryStore::control_of(
    const protocol::SessionId& view) {
    if (auto f = failure()) return *f;
    std::lock_guard lock(mutex_);
    for (const auto& [id, record] : records_) {
        if (record.view == view && view != protocol::SessionId{})
            return std::optional<protocol::SessionId>(id);
    }
    return std::optional<protocol::SessionId>();
}

StoreResult<std::vector<std::string>> MemoryStore::owners(
    std::span<const protocol::SessionId> ids) {
    if (auto f = failure()) return *f;
    std::lock_guard lock(mutex_);
    std::vector<std::string> out;
    for (const auto& id : ids) {
        auto it = records_.find(id);
        out.push_back(it == records_.end() ? std::string() : it->second.owner);
    }
    return out;
}

StoreResult<Status> MemoryStore::ping() {
    if (auto f = failure()) return *f;
    return Status::ok;
}

namespace {

class Forwarder final : public store::SessionStore {
  public:
    explicit Forwarder(MemoryStore& to) : to_(to) {}
    std::string describe() const override { return to_.describe(); }
    bool shared() const override { return to_.shared(); }
    StoreResult<Status> save(const store::SessionRecord& r) override { return to_.save(r); }
    StoreResult<Status> remove(const protocol::SessionId& id, std::string_view owner) override {
        return to_.remove(id, owner);
    }
    StoreResult<Status> touch(std::span<const store::Activity> a, std::string_view owner) override {
        return to_.touch(a, owner);
    }
    StoreResult<std::optional<store::SessionRecord>> claim(const protocol::SessionId& id,
                                                           std::string_view owner) override {
        return to_.claim(id, owner);
    }
    StoreResult<std::vector<store::SessionRecord>> claim_all(std::string_view owner,
                                                             std::uint64_t after) override {
        return to_.claim_all(owner, after);
    }
    StoreResult<std::optional<protocol::SessionId>> control_of(
        const protocol::SessionId& view) override {
        return to_.control_of(view);
    }
    StoreResult<std::vector<std::string>> owners(
        std::span<const protocol::SessionId> ids) override {
        return to_.owners(ids);
    }
    StoreResult<Status> ping() override { return to_.ping(); }

  private:
    MemoryStore& to_;
};

}  // namespace

std::unique_ptr<store::SessionStore> forward_to(MemoryStore& store) {
    return std::make_unique<Forwarder>(store);
}

}  // namespace isomesh::server::testing
