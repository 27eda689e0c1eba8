// What only the SQLite case store meets: a damaged file, a database locked
// by another process, a full disk.
#include "server/cases/open_case_store.h"

#include <gtest/gtest.h>
#include <signal.h>
#include <sys/resource.h>
#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <fstream>

#include "server/cases/case_schema.h"
#include "server/cases/sqlite_handle.h"
#include "tests/cases/case_store_test_util.h"

namespace vpm::cases {
namespace {

namespace fs = std::filesystem;

// The contract's fixture, on SQLite only.
using SqliteCaseStoreTest = CaseStoreFixture;

TEST_P(SqliteCaseStoreTest, ADamagedOrUnwritableDatabaseIsRefusedWithTheReason) {
  std::ofstream(file()) << std::string(8192, 'x');  // not a database
  auto damaged = OpenSqliteCaseStore(file());
  EXPECT_EQ(damaged.status().code(), absl::StatusCode::kDataLoss) << damaged.status();
  EXPECT_NE(damaged.status().message().find("damaged"), std::string::npos) << damaged.status();

  auto nowhere = OpenSqliteCaseStore(dir_ / "missing-folder" / "cases.sqlite");
  EXPECT_FALSE(nowhere.ok());
  EXPECT_NE(nowhere.status().message().find("case store"), std::string::npos);
}

TEST_P(SqliteCaseStoreTest, ALockedDatabaseRefusesTheEventAndKeepsWhatItHad) {
  auto store = OpenSqliteCaseStore(file(), {.busy_timeout_ms = 50});
  ASSERT_TRUE(store.ok());
  ASSERT_TRUE((*store)->Create(Record("c", "alice")).ok());
  ASSERT_TRUE((*store)->Append("c", Grab(1), 0).ok());
  sqlite3* raw = nullptr;
  ASSERT_EQ(sqlite3_open(file().c_str(), &raw), SQLITE_OK);
  SqliteDb other(raw);
  ASSERT_TRUE(other.Exec("BEGIN EXCLUSIVE", "lock").ok());
  const auto refused = (*store)->Append("c", Drag(2), 1);
  EXPECT_EQ(refused.status().code(), absl::StatusCode::kUnavailable) << refused.status();
  ASSERT_TRUE(other.Exec("ROLLBACK", "unlock").ok());
  EXPECT_EQ((*store)->Events("c")->size(), 1u);
  EXPECT_EQ(*(*store)->Append("c", Drag(2), 1), 2);
}

// A full disk, as a file size limit (RLIMIT_FSIZE, SIGXFSZ ignored: writes
// past it fail with EFBIG): the event is refused with ResourceExhausted,
// nothing of it is stored, and once there is room again events are stored.
TEST_P(SqliteCaseStoreTest, AFullDiskRefusesTheEventWholeAndTheStoreGoesOnAfterwards) {
  auto store = Open();
  ASSERT_TRUE(store);
  ASSERT_TRUE(store->Create(Record("c", "alice")).ok());
  ASSERT_TRUE(store->Append("c", Grab(1), 0).ok());
  rlimit old{};
  ASSERT_EQ(getrlimit(RLIMIT_FSIZE, &old), 0);
  signal(SIGXFSZ, SIG_IGN);
  rlimit limited = old;
  limited.rlim_cur = fs::file_size(dir_ / "cases.sqlite-wal") + 64 * 1024;
  ASSERT_EQ(setrlimit(RLIMIT_FSIZE, &limited), 0);
  Status refused = absl::OkStatus();
  int stored = 0;
  for (int i = 0; i < 10000 && refused.ok(); ++i) {
    Result<int64_t> seq = store->Append("c", Drag(i), double(i));
    refused = seq.status();
    if (seq.ok()) ++stored;
  }
  ASSERT_EQ(setrlimit(RLIMIT_FSIZE, &old), 0);
  signal(SIGXFSZ, SIG_DFL);
  std::printf("stored %d events before the limit; refused: %s\n", stored,
              std::string(refused.message()).c_str());
  EXPECT_EQ(refused.code(), absl::StatusCode::kResourceExhausted) << refused;
  EXPECT_NE(refused.message().find("free space"), std::string::npos) << refused;
  // The refused event is not there; every acknowledged one is.
  auto events = store->Events("c");
  ASSERT_TRUE(events.ok()) << events.status();
  EXPECT_EQ(int(events->size()), 1 + stored);
  // Room again: the store goes on, and a reopen sees the same.
  ASSERT_TRUE(store->Append("c", Drag(-1), 0).ok());
  store.reset();
  auto again = Open();
  ASSERT_TRUE(again);
  EXPECT_EQ(int(again->Events("c")->size()), 2 + stored);
}

INSTANTIATE_TEST_SUITE_P(Sqlite, SqliteCaseStoreTest, ::testing::Values(Backend::kSqlite),
                         BackendName);

}  // namespace
}  // namespace vpm::cases
