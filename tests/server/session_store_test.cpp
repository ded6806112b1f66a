// The session stores against the real engines: SQLite on a temporary file, Redis as a
// redis-server of the test's own (tests/server/redis_process.h). The same contract for both
// (server/store/session_store.h), then what each adds.
#include <gtest/gtest.h>

#include <sqlite3.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <functional>
#include <memory>
#include <thread>

#include "redis_process.h"
#include "server/store/redis_store.h"
#include "server/store/session_store.h"
#include "server/store/sqlite_store.h"

namespace isomesh::server::store {
namespace {

using testing::RedisProcess;

protocol::SessionId id_of(std::uint8_t n) {
    protocol::SessionId id;
    id.bytes.fill(n);
    return id;
}

SessionRecord record(std::uint8_t n, std::string owner, std::uint32_t version = 1) {
    SessionRecord r;
    r.id = id_of(n);
    r.version = version;
    r.definition = R"({"v":1,"type":"create","expression":"x^2+y^2+z^2=)" + std::to_string(n) +
                   R"(","box":[-3,3,-3,3,-3,3]})";
    r.owner = std::move(owner);
    r.created_us = 1'700'000'000'000'000ull + n;
    r.active_us = r.created_us + 10;
    return r;
}

/// A temporary SQLite file, removed afterwards.
struct TemporaryFile {
    TemporaryFile()
        : path(std::filesystem::temp_directory_path() /
               ("isomesh-store-test-" + std::to_string(getpid()) + "-" + std::to_string(counter++) +
                ".db")) {}
    ~TemporaryFile() {
        for (const char* suffix : {"", "-wal", "-shm"})
            std::filesystem::remove(path.string() + suffix);
    }
    std::filesystem::path path;
    static inline int counter = 0;
};

/// One store under test with whatever keeps it alive (its file, its Redis).
struct StoreUnderTest {
    std::shared_ptr<void> holder;
    std::unique_ptr<SessionStore> store;
};

struct StoreKind {
    const char* name;
    std::function<StoreUnderTest()> open;
};

StoreUnderTest open_sqlite() {
    auto file = std::make_shared<TemporaryFile>();
    auto store = SqliteStore::open(file->path.string());
    EXPECT_TRUE(store.ok()) << (store ? "" : store.error().message);
    return {file, store ? std::unique_ptr<SessionStore>(std::move(store).value()) : nullptr};
}

StoreUnderTest open_redis() {
    auto redis = std::make_shared<RedisProcess>();
    EXPECT_TRUE(redis->ok()) << redis->error();
    return {redis, std::make_unique<RedisStore>("127.0.0.1", redis->port(), 3600)};
}

class SessionStoreContract : public ::testing::TestWithParam<StoreKind> {
  protected:
    void SetUp() override {
        under_test_ = GetParam().open();
        ASSERT_NE(under_test_.store, nullptr);
    }
    SessionStore& store() { return *under_test_.store; }

  private:
    StoreUnderTest under_test_;
};

INSTANTIATE_TEST_SUITE_P(SessionStore, SessionStoreContract,
                         ::testing::Values(StoreKind{"sqlite", open_sqlite},
                                           StoreKind{"redis", open_redis}),
                         [](const auto& info) { return std::string(info.param.name); });

TEST_P(SessionStoreContract, saves_and_claims_a_record_keeping_its_creation_time) {
    const SessionRecord first = record(1, "a");
    ASSERT_EQ(store().save(first).value(), Status::ok);
    SessionRecord second = record(1, "a", 2);
    second.definition = R"({"v":1,"type":"create","expression":"x=0","box":[0,1,0,1,0,1]})";
    second.created_us = 5;  // ignored: the record keeps the time it was created
    second.active_us = first.active_us + 100;
    ASSERT_EQ(store().save(second).value(), Status::ok);

    const auto claimed = store().claim(first.id, "b");
    ASSERT_TRUE(claimed.ok());
    ASSERT_TRUE(claimed.value().has_value());
    const SessionRecord& got = *claimed.value();
    EXPECT_EQ(got.version, 2u);
    EXPECT_EQ(got.definition, second.definition);
    EXPECT_EQ(got.created_us, first.created_us);
    EXPECT_EQ(got.active_us, second.active_us);
    EXPECT_EQ(got.owner, "b");
    EXPECT_FALSE(store().claim(id_of(9), "b").value().has_value()) << "no such record";
}

TEST_P(SessionStoreContract, writes_of_another_owner_are_refused) {
    ASSERT_EQ(store().save(record(1, "a")).value(), Status::ok);
    ASSERT_TRUE(store().claim(id_of(1), "b").value());  // b serves it from now on
    EXPECT_EQ(store().save(record(1, "a", 2)).value(), Status::not_owner);
    EXPECT_EQ(store().remove(id_of(1), "a").value(), Status::not_owner);
    const Activity activity{id_of(1), 42};
    ASSERT_TRUE(store().touch(std::span(&activity, 1), "a").ok());
    const auto kept = store().claim(id_of(1), "b").value();
    ASSERT_TRUE(kept);
    EXPECT_EQ(kept->version, 1u);
    EXPECT_NE(kept->active_us, 42u);
    EXPECT_EQ(store().remove(id_of(1), "b").value(), Status::ok);
    EXPECT_EQ(store().remove(id_of(1), "b").value(), Status::missing);
}

TEST_P(SessionStoreContract, owners_and_touch_name_records_by_id) {
    for (std::uint8_t n = 1; n <= 3; ++n)
        ASSERT_EQ(store().save(record(n, "a")).value(), Status::ok);
    ASSERT_TRUE(store().claim(id_of(2), "b").value());
    const std::vector<protocol::SessionId> ids = {id_of(1), id_of(2), id_of(3), id_of(4)};
    EXPECT_EQ(store().owners(ids).value(), (std::vector<std::string>{"a", "b", "a", ""}));
    const std::vector<Activity> activity = {{id_of(1), 111}, {id_of(3), 333}};
    ASSERT_TRUE(store().touch(activity, "a").ok());
    EXPECT_EQ(store().claim(id_of(3), "a").value()->active_us, 333u);
    EXPECT_TRUE(store().ping().ok());
}

TEST_P(SessionStoreContract, finds_a_record_by_its_view_id_until_it_is_deleted) {
    SessionRecord first = record(1, "a");
    first.view = id_of(101);
    ASSERT_EQ(store().save(first).value(), Status::ok);
    ASSERT_EQ(store().save(record(2, "a")).value(), Status::ok);  // view id unknown
    EXPECT_EQ(store().control_of(id_of(101)).value(), id_of(1));
    EXPECT_FALSE(store().control_of(id_of(102)).value()) << "no record has this view id";
    EXPECT_FALSE(store().control_of(protocol::SessionId{}).value()) << "unknown is not an id";
    const auto claimed = store().claim(id_of(1), "b").value();
    ASSERT_TRUE(claimed);
    EXPECT_EQ(claimed->view, id_of(101));
    EXPECT_EQ(store().claim(id_of(2), "b").value()->view, protocol::SessionId{});
    ASSERT_EQ(store().remove(id_of(1), "b").value(), Status::ok);
    EXPECT_FALSE(store().control_of(id_of(101)).value());
}

TEST(SqliteStore, a_database_made_before_view_ids_gets_the_column_and_keeps_its_records) {
    TemporaryFile file;
    {
        sqlite3* db = nullptr;
        ASSERT_EQ(sqlite3_open(file.path.c_str(), &db), SQLITE_OK);
        const char* old_schema =
            "CREATE TABLE sessions (id TEXT PRIMARY KEY, owner TEXT NOT NULL, version INTEGER NOT "
            "NULL, definition TEXT NOT NULL, created_us INTEGER NOT NULL, active_us INTEGER NOT "
            "NULL);"
            "INSERT INTO sessions VALUES ('01010101010101010101010101010101', 'old', 3, '{}', 1, "
            "2);";
        ASSERT_EQ(sqlite3_exec(db, old_schema, nullptr, nullptr, nullptr), SQLITE_OK);
        sqlite3_close(db);
    }
    auto store = SqliteStore::open(file.path.string());
    ASSERT_TRUE(store.ok()) << store.error().message;
    const auto records = store.value()->claim_all("new", 0).value();
    ASSERT_EQ(records.size(), 1u);
    EXPECT_EQ(records[0].id, id_of(1));
    EXPECT_EQ(records[0].version, 3u);
    EXPECT_EQ(records[0].view, protocol::SessionId{});
    SessionRecord updated = records[0];
    updated.view = id_of(7);
    ASSERT_EQ(store.value()->save(updated).value(), Status::ok);
    EXPECT_EQ(store.value()->control_of(id_of(7)).value(), id_of(1));
}

TEST(SqliteStore, claim_all_deletes_idle_records_and_takes_the_others) {
    TemporaryFile file;
    auto store = SqliteStore::open(file.path.string());
    ASSERT_TRUE(store.ok());
    SessionRecord idle = record(1, "old");
    idle.active_us = 100;
    ASSERT_EQ(store.value()->save(idle).value(), Status::ok);
    ASSERT_EQ(store.value()->save(record(2, "old")).value(), Status::ok);
    const auto records = store.value()->claim_all("new", 1000);
    ASSERT_TRUE(records.ok());
    ASSERT_EQ(records.value().size(), 1u);
    EXPECT_EQ(records.value()[0].id, id_of(2));
    EXPECT_EQ(store.value()->owners(std::vector{id_of(1), id_of(2)}).value(),
              (std::vector<std::string>{"", "new"}));
}

TEST(SqliteStore, a_second_server_on_the_same_file_is_refused_and_records_survive_reopening) {
    TemporaryFile file;
    {
        auto first = SqliteStore::open(file.path.string());
        ASSERT_TRUE(first.ok());
        ASSERT_EQ(first.value()->save(record(1, "a")).value(), Status::ok);
        auto second = SqliteStore::open(file.path.string());
        ASSERT_FALSE(second.ok());
        EXPECT_NE(second.error().message.find("another isomesh-server"), std::string::npos)
            << second.error().message;
    }
    auto reopened = SqliteStore::open(file.path.string());
    ASSERT_TRUE(reopened.ok());
    EXPECT_EQ(reopened.value()->claim_all("b", 0).value(), (std::vector{[] {
                  SessionRecord r = record(1, "b");
                  return r;
              }()}));
}

TEST(RedisStore, fails_while_redis_is_down_and_works_again_once_it_is_back) {
    RedisProcess redis;
    ASSERT_TRUE(redis.ok()) << redis.error();
    RedisStore store("127.0.0.1", redis.port(), 3600);
    ASSERT_EQ(store.save(record(1, "a")).value(), Status::ok);
    redis.stop();
    const auto failed = store.save(record(2, "a"));
    ASSERT_FALSE(failed.ok());
    EXPECT_NE(failed.error().message.find("redis://127.0.0.1"), std::string::npos)
        << failed.error().message;
    EXPECT_FALSE(store.ping().ok());
    ASSERT_TRUE(redis.start());
    EXPECT_TRUE(store.ping().ok());
    EXPECT_EQ(store.save(record(2, "a")).value(), Status::ok);
}

TEST(RedisStore, records_nobody_touches_expire_after_their_time_to_live) {
    RedisProcess redis;
    ASSERT_TRUE(redis.ok()) << redis.error();
    RedisStore store("127.0.0.1", redis.port(), 1);
    ASSERT_EQ(store.save(record(1, "a")).value(), Status::ok);
    std::this_thread::sleep_for(std::chrono::milliseconds(2100));
    EXPECT_EQ(store.owners(std::vector{id_of(1)}).value(), std::vector<std::string>{""});
}

TEST(StoreSpec, parses_none_sqlite_and_redis) {
    EXPECT_EQ(parse_store_spec("none")->kind, StoreSpec::Kind::none);
    const auto sqlite = parse_store_spec("sqlite:/var/lib/isomesh/sessions.db");
    ASSERT_TRUE(sqlite);
    EXPECT_EQ(sqlite->path, "/var/lib/isomesh/sessions.db");
    const auto redis = parse_store_spec("redis://redis:6380");
    ASSERT_TRUE(redis);
    EXPECT_EQ(redis->host, "redis");
    EXPECT_EQ(redis->port, 6380);
    EXPECT_EQ(parse_store_spec("redis://10.0.0.1")->port, 6379);
    for (const char* bad : {"", "sqlite:", "redis://", "redis://h:0", "redis://h:99999",
                            "redis://user@h:1", "mysql://h", "memory"})
        EXPECT_FALSE(parse_store_spec(bad)) << bad;
}

}  // namespace
}  // namespace isomesh::server::store
