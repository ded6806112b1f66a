// A session store in memory for the service tests: the contract of server/store/session_store.h
// with a switch that makes every call fail, as a store that is down does, and a count of calls.
// One MemoryStore may back several services (a shared store).
#pragma once

#include <atomic>
#include <map>
#include <mutex>

#include "server/store/session_store.h"

namespace isomesh::server::testing {

class MemoryStore final : public store::SessionStore {
  public:
    explicit MemoryStore(bool shared = false) : shared_(shared) {}

    std::atomic<bool> down{false};

    std::optional<store::SessionRecord> find(const protocol::SessionId& id) const;
    std::size_t size() const;

    std::string describe() const override { return "memory"; }
    bool shared() const override { return shared_; }
    store::StoreResult<store::Status> save(const store::SessionRecord& record) override;
    store::StoreResult<store::Status> remove(const protocol::SessionId& id,
                                             std::string_view owner) override;
    store::StoreResult<store::Status> touch(std::span<const store::Activity> activity,
                                            std::string_view owner) override;
    store::StoreResult<std::optional<store::SessionRecord>> claim(const protocol::SessionId& id,
                                                                  std::string_view owner) override;
    store::StoreResult<std::vector<store::SessionRecord>> claim_all(
        std::string_view owner, std::uint64_t active_after_us) override;
    store::StoreResult<std::optional<protocol::SessionId>> control_of(
        const protocol::SessionId& view) override;
    store::StoreResult<std::vector<std::string>> owners(
        std::span<const protocol::SessionId> ids) override;
    store::StoreResult<store::Status> ping() override;

  private:
    /// The failure of a call while down, or nothing.
    std::optional<store::StoreError> failure() const;

    const bool shared_;
    mutable std::mutex mutex_;
    std::map<protocol::SessionId, store::SessionRecord> records_;
};

/// A service's store handed over while the test keeps using it: the service owns a forwarder.
std::unique_ptr<store::SessionStore> forward_to(MemoryStore& store);

}  // namespace isomesh::server::testing
