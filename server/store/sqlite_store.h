// The embedded session store: one SQLite database file (Debian's libsqlite3) in WAL mode.
//
// Durability: every write is a committed transaction before save() returns. With WAL and
// synchronous=NORMAL a commit survives the crash of the server process (kill -9, out of memory);
// an operating-system crash or a power cut may lose the last commits. The database is opened in
// exclusive locking mode, so a second server started on the same file fails at once instead of
// sharing sessions it cannot coordinate (use Redis for several servers).
#pragma once

#include <memory>
#include <mutex>
#include <string>

#include "server/store/session_store.h"

struct sqlite3;

namespace isomesh::server::store {

class SqliteStore final : public SessionStore {
  public:
    /// Opens (creating if needed) the database at `path`; its folder must exist.
    static StoreResult<std::unique_ptr<SqliteStore>> open(const std::string& path);
    ~SqliteStore() override;

    std::string describe() const override { return "sqlite:" + path_; }
    bool shared() const override { return false; }
    StoreResult<Status> save(const SessionRecord& record) override;
    StoreResult<Status> remove(const protocol::SessionId& id, std::string_view owner) override;
    StoreResult<Status> touch(std::span<const Activity> activity, std::string_view owner) override;
    StoreResult<std::optional<SessionRecord>> claim(const protocol::SessionId& id,
                                                    std::string_view owner) override;
    StoreResult<std::vector<SessionRecord>> claim_all(std::string_view owner,
                                                      std::uint64_t active_after_us) override;
    StoreResult<std::optional<protocol::SessionId>> control_of(
        const protocol::SessionId& view) override;
    StoreResult<std::vector<std::string>> owners(std::span<const protocol::SessionId> ids) override;
    StoreResult<Status> ping() override;

  private:
    class Statement;
    SqliteStore(sqlite3* db, std::string path);
    /// Runs statements without results (schema, BEGIN, COMMIT); the error text or nothing.
    std::optional<std::string> execute(const char* sql);
    StoreError error(std::string_view what) const;
    StoreResult<std::vector<SessionRecord>> select_all();

    sqlite3* db_;
    const std::string path_;
    std::mutex mutex_;
};

}  // namespace isomesh::server::store
