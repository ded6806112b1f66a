#include "server/store/sqlite_store.h"

#include <sqlite3.h>

namespace isomesh::server::store {
namespace {

constexpr const char* kSchema =
    "CREATE TABLE IF NOT EXISTS sessions ("
    "  id TEXT PRIMARY KEY,"  // 32 hex digits
    "  owner TEXT NOT NULL,"
    "  version INTEGER NOT NULL,"
    "  definition TEXT NOT NULL,"
    "  created_us INTEGER NOT NULL,"
    "  active_us INTEGER NOT NULL,"
    "  view TEXT NOT NULL DEFAULT '')";  // 32 hex digits, '' when unknown

// Databases made before view ids were kept get the column; then the index finds records by it.
constexpr const char* kAddView = "ALTER TABLE sessions ADD COLUMN view TEXT NOT NULL DEFAULT ''";
constexpr const char* kViewIndex = "CREATE INDEX IF NOT EXISTS sessions_by_view ON sessions (view)";

// A new record, or a new version of one the same owner holds (created_us is kept).
constexpr const char* kSave =
    "INSERT INTO sessions (id, owner, version, definition, created_us, active_us, view)"
    " VALUES (?1, ?2, ?3, ?4, ?5, ?6, ?7)"
    " ON CONFLICT (id) DO UPDATE SET version = excluded.version,"
    "   definition = excluded.definition, active_us = excluded.active_us, view = excluded.view"
    " WHERE sessions.owner = excluded.owner";

std::int64_t to_sql(std::uint64_t value) {
    return static_cast<std::int64_t>(value);
}

std::string view_text(const protocol::SessionId& view) {
    return view == protocol::SessionId{} ? std::string() : view.to_hex();
}

protocol::SessionId view_of(const std::string& text) {
    return protocol::SessionId::from_hex(text).value_or(protocol::SessionId{});
}

}  // namespace

/// A prepared statement, finalized on destruction.
class SqliteStore::Statement {
  public:
    Statement(sqlite3* db, const char* sql) : db_(db) {
        if (sqlite3_prepare_v2(db, sql, -1, &statement_, nullptr) != SQLITE_OK)
            statement_ = nullptr;
    }
    ~Statement() { sqlite3_finalize(statement_); }
    Statement(const Statement&) = delete;
    Statement& operator=(const Statement&) = delete;

    bool ok() const { return statement_ != nullptr; }
    Statement& bind(int index, std::string_view text) {
        sqlite3_bind_text(statement_, index, text.data(), static_cast<int>(text.size()),
                          SQLITE_TRANSIENT);
        return *this;
    }
    Statement& bind(int index, std::int64_t value) {
        sqlite3_bind_int64(statement_, index, value);
        return *this;
    }
    /// SQLITE_ROW, SQLITE_DONE or an error code.
    int step() { return sqlite3_step(statement_); }
    void reset() {
        sqlite3_reset(statement_);
        sqlite3_clear_bindings(statement_);
    }
    std::string text(int column) const {
        const auto* data = sqlite3_column_text(statement_, column);
        return data
                   ? std::string(reinterpret_cast<const char*>(data),
                                 static_cast<std::size_t>(sqlite3_column_bytes(statement_, column)))
                   : std::string();
    }
    std::int64_t integer(int column) const { return sqlite3_column_int64(statement_, column); }
    /// Rows changed by the last step of a write.
    int changes() const { return sqlite3_changes(db_); }

  private:
    sqlite3* db_;
    sqlite3_stmt* statement_ = nullptr;
};

StoreResult<std::unique_ptr<SqliteStore>> SqliteStore::open(const std::string& path) {
    sqlite3* db = nullptr;
    const int flags = SQLITE_OPEN_READWRITE | SQLITE_OPEN_CREATE | SQLITE_OPEN_NOMUTEX;
    if (sqlite3_open_v2(path.c_str(), &db, flags, nullptr) != SQLITE_OK) {
        StoreError error{"cannot open " + path + ": " +
                         (db ? sqlite3_errmsg(db) : std::string("out of memory"))};
        sqlite3_close(db);
        return error;
    }
    std::unique_ptr<SqliteStore> store(new SqliteStore(db, path));
    // Exclusive locking: the first write takes the file's lock and keeps it while this server
    // runs, so a second server on the same file fails here ("database is locked").
    for (const char* sql : {"PRAGMA locking_mode = EXCLUSIVE", "PRAGMA journal_mode = WAL",
                            "PRAGMA synchronous = NORMAL", kSchema}) {
        if (auto problem = store->execute(sql)) {
            return StoreError{"cannot use " + path + " (" + *problem +
                              "; is another isomesh-server using it?)"};
        }
    }
    if (!Statement(db, "SELECT view FROM sessions LIMIT 0").ok()) {
        if (auto problem = store->execute(kAddView))
            return StoreError{"cannot add the view column to " + path + ": " + *problem};
    }
    if (auto problem = store->execute(kViewIndex))
        return StoreError{"cannot index " + path + ": " + *problem};
    return store;
}

SqliteStore::SqliteStore(sqlite3* db, std::string path) : db_(db), path_(std::move(path)) {}

SqliteStore::~SqliteStore() {
    sqlite3_close(db_);
}

std::optional<std::string> SqliteStore::execute(const char* sql) {
    char* message = nullptr;
    if (sqlite3_exec(db_, sql, nullptr, nullptr, &message) == SQLITE_OK) return std::nullopt;
    std::string text = message ? message : sqlite3_errmsg(db_);
    sqlite3_free(message);
    return text;
}

StoreError SqliteStore::error(std::string_view what) const {
    return StoreError{"sqlite " + std::string(what) + ": " + sqlite3_errmsg(db_)};
}

StoreResult<Status> SqliteStore::save(const SessionRecord& record) {
    std::lock_guard lock(mutex_);
    Statement save(db_, kSave);
    if (!save.ok()) return error("save");
    save.bind(1, record.id.to_hex())
        .bind(2, record.owner)
        .bind(3, std::int64_t{record.version})
        .bind(4, record.definition)
        .bind(5, to_sql(record.created_us))
        .bind(6, to_sql(record.active_us))
        .bind(7, view_text(record.view));
    if (save.step() != SQLITE_DONE) return error("save");
    return save.changes() == 0 ? Status::not_owner : Status::ok;
}

StoreResult<Status> SqliteStore::remove(const protocol::SessionId& id, std::string_view owner) {
    std::lock_guard lock(mutex_);
    Statement remove(db_, "DELETE FROM sessions WHERE id = ?1 AND owner = ?2");
    if (!remove.ok()) return error("remove");
    remove.bind(1, id.to_hex()).bind(2, owner);
    if (remove.step() != SQLITE_DONE) return error("remove");
    if (remove.changes() > 0) return Status::ok;
    Statement exists(db_, "SELECT 1 FROM sessions WHERE id = ?1");
    if (!exists.ok()) return error("remove");
    exists.bind(1, id.to_hex());
    const int found = exists.step();
    if (found != SQLITE_ROW && found != SQLITE_DONE) return error("remove");
    return found == SQLITE_ROW ? Status::not_owner : Status::missing;
}

StoreResult<Status> SqliteStore::touch(std::span<const Activity> activity, std::string_view owner) {
    std::lock_guard lock(mutex_);
    if (auto problem = execute("BEGIN")) return StoreError{"sqlite touch: " + *problem};
    Statement touch(db_, "UPDATE sessions SET active_us = ?1 WHERE id = ?2 AND owner = ?3");
    bool failed = !touch.ok();
    for (std::size_t i = 0; i < activity.size() && !failed; ++i) {
        touch.bind(1, to_sql(activity[i].active_us))
            .bind(2, activity[i].id.to_hex())
            .bind(3, owner);
        failed = touch.step() != SQLITE_DONE;
        touch.reset();
    }
    if (failed) {
        StoreError problem = error("touch");
        execute("ROLLBACK");
        return problem;
    }
    if (auto problem = execute("COMMIT")) return StoreError{"sqlite touch: " + *problem};
    return Status::ok;
}

StoreResult<std::optional<SessionRecord>> SqliteStore::claim(const protocol::SessionId& id,
                                                             std::string_view owner) {
    std::lock_guard lock(mutex_);
    Statement claim(db_, "UPDATE sessions SET owner = ?1 WHERE id = ?2");
    Statement read(db_,
                   "SELECT version, definition, created_us, active_us, view FROM sessions"
                   " WHERE id = ?1");
    if (!claim.ok() || !read.ok()) return error("claim");
    claim.bind(1, owner).bind(2, id.to_hex());
    if (claim.step() != SQLITE_DONE) return error("claim");
    if (claim.changes() == 0) return std::optional<SessionRecord>();
    read.bind(1, id.to_hex());
    if (read.step() != SQLITE_ROW) return error("claim");
    SessionRecord record;
    record.id = id;
    record.owner = std::string(owner);
    record.version = static_cast<std::uint32_t>(read.integer(0));
    record.definition = read.text(1);
    record.created_us = static_cast<std::uint64_t>(read.integer(2));
    record.active_us = static_cast<std::uint64_t>(read.integer(3));
    record.view = view_of(read.text(4));
    return std::optional<SessionRecord>(std::move(record));
}

StoreResult<std::vector<SessionRecord>> SqliteStore::claim_all(std::string_view owner,
                                                               std::uint64_t active_after_us) {
    std::lock_guard lock(mutex_);
    if (auto problem = execute("BEGIN")) return StoreError{"sqlite claim_all: " + *problem};
    Statement purge(db_, "DELETE FROM sessions WHERE active_us < ?1");
    Statement claim(db_, "UPDATE sessions SET owner = ?1");
    bool failed = !purge.ok() || !claim.ok();
    if (!failed) failed = purge.bind(1, to_sql(active_after_us)).step() != SQLITE_DONE;
    if (!failed) failed = claim.bind(1, owner).step() != SQLITE_DONE;
    if (failed) {
        StoreError problem = error("claim_all");
        execute("ROLLBACK");
        return problem;
    }
    auto records = select_all();
    if (!records) {
        execute("ROLLBACK");
        return records;
    }
    if (auto problem = execute("COMMIT")) return StoreError{"sqlite claim_all: " + *problem};
    return records;
}

StoreResult<std::vector<SessionRecord>> SqliteStore::select_all() {
    Statement all(db_,
                  "SELECT id, owner, version, definition, created_us, active_us, view FROM sessions"
                  " ORDER BY created_us");
    if (!all.ok()) return error("select");
    std::vector<SessionRecord> records;
    int step = SQLITE_ROW;
    while ((step = all.step()) == SQLITE_ROW) {
        auto id = protocol::SessionId::from_hex(all.text(0));
        if (!id) continue;  // not written by isomesh: ignored
        SessionRecord record;
        record.id = *id;
        record.owner = all.text(1);
        record.version = static_cast<std::uint32_t>(all.integer(2));
        record.definition = all.text(3);
        record.created_us = static_cast<std::uint64_t>(all.integer(4));
        record.active_us = static_cast<std::uint64_t>(all.integer(5));
        record.view = view_of(all.text(6));
        records.push_back(std::move(record));
    }
    if (step != SQLITE_DONE) return error("select");
    return records;
}

StoreResult<std::optional<protocol::SessionId>> SqliteStore::control_of(
    const protocol::SessionId& view) {
    std::lock_guard lock(mutex_);
    Statement find(db_, "SELECT id FROM sessions WHERE view = ?1");
    if (!find.ok()) return error("control_of");
    find.bind(1, view_text(view));
    const int step = find.step();
    if (step != SQLITE_ROW && step != SQLITE_DONE) return error("control_of");
    if (step == SQLITE_DONE || view == protocol::SessionId{})
        return std::optional<protocol::SessionId>();
    return protocol::SessionId::from_hex(find.text(0));
}

StoreResult<std::vector<std::string>> SqliteStore::owners(
    std::span<const protocol::SessionId> ids) {
    std::lock_guard lock(mutex_);
    Statement owner(db_, "SELECT owner FROM sessions WHERE id = ?1");
    if (!owner.ok()) return error("owners");
    std::vector<std::string> out;
    for (const protocol::SessionId& id : ids) {
        owner.bind(1, id.to_hex());
        const int step = owner.step();
        if (step != SQLITE_ROW && step != SQLITE_DONE) return error("owners");
        out.push_back(step == SQLITE_ROW ? owner.text(0) : std::string());
        owner.reset();
    }
    return out;
}

StoreResult<Status> SqliteStore::ping() {
    std::lock_guard lock(mutex_);
    Statement count(db_, "SELECT count(*) FROM sessions");
    if (!count.ok() || count.step() != SQLITE_ROW) return error("ping");
    return Status::ok;
}

}  // namespace isomesh::server::store
