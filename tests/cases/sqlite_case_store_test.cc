// The SQLite case store against a temporary folder.
#include "server/cases/sqlite_case_store.h"

#include <gtest/gtest.h>
#include <signal.h>
#include <sys/resource.h>
#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <fstream>

#include "server/cases/case_schema.h"

namespace vpm::cases {
namespace {

namespace fs = std::filesystem;

class CaseStoreTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("vpm-case-store-" + std::to_string(::getpid()) + "-" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  fs::path file() const { return dir_ / "cases.sqlite"; }
  std::unique_ptr<CaseStore> Open() {
    auto store = OpenSqliteCaseStore(file());
    EXPECT_TRUE(store.ok()) << store.status();
    return store.ok() ? std::move(*store) : nullptr;
  }
  static CaseRecord Record(const std::string& id, const std::string& owner) {
    return {.id = id, .owner = owner, .title = "left kidney", .source = "ct/abdomen.nii.gz",
            .mesh_params = std::string("\x10\x20\0", 3)};
  }
  static SceneOp Grab(double x) {
    return {.kind = SceneOp::Kind::kGrab, .grab = {.point_mm = {x, 2.0, 3.0}, .radius_mm = 4.5}};
  }
  static SceneOp Drag(double z) { return {.kind = SceneOp::Kind::kDrag, .vector = {0, 0, z}}; }
  static SceneOp Release(bool keep) { return {.kind = SceneOp::Kind::kRelease, .keep = keep}; }

  fs::path dir_;
};

TEST_F(CaseStoreTest, EventsAreKeptInOrderAcrossAReopen) {
  {
    auto store = Open();
    ASSERT_TRUE(store);
    ASSERT_TRUE(store->Create(Record("case-1", "alice")).ok());
    EXPECT_EQ(*store->Append("case-1", Grab(1.0), 0.0), 1);
    EXPECT_EQ(*store->Append("case-1", Drag(5.0), 4.25), 2);
    EXPECT_EQ(*store->Append("case-1", Release(true), 4.0), 3);
    EXPECT_EQ(store->Append("case-9", Grab(1.0), 0.0).status().code(),
              absl::StatusCode::kNotFound);
  }
  auto store = Open();
  ASSERT_TRUE(store);
  auto events = store->Events("case-1");
  ASSERT_TRUE(events.ok()) << events.status();
  ASSERT_EQ(events->size(), 3u);
  EXPECT_EQ((*events)[0].op.kind, SceneOp::Kind::kGrab);
  EXPECT_EQ((*events)[0].op.grab.point_mm, glm::dvec3(1.0, 2.0, 3.0));
  EXPECT_EQ((*events)[0].op.grab.radius_mm, 4.5);
  EXPECT_EQ((*events)[1].op.vector, glm::dvec3(0.0, 0.0, 5.0));
  EXPECT_TRUE((*events)[2].op.keep);
  auto record = store->Get("case-1");
  ASSERT_TRUE(record.ok());
  EXPECT_EQ(record->events, 3);
  EXPECT_EQ(record->max_displacement_mm, 4.0);
  EXPECT_EQ(record->mesh_params, std::string("\x10\x20\0", 3));  // bytes, not text
  EXPECT_EQ(record->source, "ct/abdomen.nii.gz");
}

TEST_F(CaseStoreTest, UndoTakesBackWholeActionsAndANewEventDropsTheRedo) {
  auto store = Open();
  ASSERT_TRUE(store);
  ASSERT_TRUE(store->Create(Record("c", "alice")).ok());
  for (const SceneOp& op : {Grab(1), Drag(1), Drag(2), Release(true), Grab(7), Drag(3)}) {
    ASSERT_TRUE(store->Append("c", op, 1.0).ok());
  }
  EXPECT_TRUE(*store->Undo("c"));  // the second grab and its drag
  EXPECT_EQ(store->Events("c")->size(), 4u);
  EXPECT_EQ(store->Get("c")->undone, 2);
  EXPECT_TRUE(*store->Undo("c"));  // the first grab, drags and release
  EXPECT_EQ(store->Events("c")->size(), 0u);
  EXPECT_FALSE(*store->Undo("c"));
  EXPECT_TRUE(*store->Redo("c"));  // the first action only
  EXPECT_EQ(store->Events("c")->size(), 4u);
  // A new event after an undo: the undone second action is gone for good.
  ASSERT_TRUE(store->Append("c", Grab(9), 0.0).ok());
  EXPECT_FALSE(*store->Redo("c"));
  auto events = store->Events("c");
  ASSERT_EQ(events->size(), 5u);
  EXPECT_EQ(events->back().op.grab.point_mm.x, 9.0);
  EXPECT_EQ(events->back().seq, 5);
}

TEST_F(CaseStoreTest, ListsOwnAndSharedCasesAndDeleteRemovesEverything) {
  auto store = Open();
  ASSERT_TRUE(store);
  ASSERT_TRUE(store->Create(Record("a1", "alice")).ok());
  ASSERT_TRUE(store->Create(Record("b1", "bob")).ok());
  EXPECT_EQ(store->Create(Record("a1", "alice")).code(), absl::StatusCode::kAlreadyExists);
  ASSERT_TRUE(store->Append("a1", Grab(1), 0).ok());
  ASSERT_TRUE(store->Share("a1", "bob", false).ok());
  auto bobs = store->List("bob");
  ASSERT_TRUE(bobs.ok());
  ASSERT_EQ(bobs->size(), 2u);
  auto alices = store->List("alice");
  ASSERT_EQ(alices->size(), 1u);
  EXPECT_EQ((*alices)[0].shared_with, std::vector<std::string>{"bob"});
  ASSERT_TRUE(store->Update("a1", std::string("right kidney"), std::nullopt).ok());
  EXPECT_EQ(store->Get("a1")->title, "right kidney");
  EXPECT_EQ(store->Get("a1")->notes, "");
  ASSERT_TRUE(store->Share("a1", "bob", true).ok());
  EXPECT_EQ(store->List("bob")->size(), 1u);

  ASSERT_TRUE(store->Share("a1", "carol", false).ok());
  ASSERT_TRUE(store->Delete("a1").ok());
  EXPECT_EQ(store->Get("a1").status().code(), absl::StatusCode::kNotFound);
  EXPECT_EQ(store->Events("a1").status().code(), absl::StatusCode::kNotFound);
  EXPECT_EQ(store->Delete("a1").code(), absl::StatusCode::kNotFound);
  // Nothing of it is left in the file: no events, no shares.
  store.reset();
  SqliteDb db;
  sqlite3* raw = nullptr;
  ASSERT_EQ(sqlite3_open(file().c_str(), &raw), SQLITE_OK);
  db = SqliteDb(raw);
  auto count = [&](const char* sql) {
    auto q = SqliteStatement::Prepare(db, sql);
    EXPECT_TRUE(q.ok());
    EXPECT_TRUE(*q->Step("count"));
    return q->Int(0);
  };
  EXPECT_EQ(count("SELECT count(*) FROM events WHERE case_id = 'a1'"), 0);
  EXPECT_EQ(count("SELECT count(*) FROM case_shares WHERE case_id = 'a1'"), 0);
  EXPECT_EQ(count("SELECT count(*) FROM cases"), 1);
}

TEST_F(CaseStoreTest, ADatabaseOfThePreviousSchemaOpensAfterMigration) {
  {
    sqlite3* raw = nullptr;
    ASSERT_EQ(sqlite3_open(file().c_str(), &raw), SQLITE_OK);
    SqliteDb db(raw);
    ASSERT_TRUE(MigrateCaseSchema(db, kCaseSchemaVersion - 1).ok());
    ASSERT_EQ(*CaseSchemaVersion(db), kCaseSchemaVersion - 1);
    ASSERT_TRUE(db.Exec("INSERT INTO cases(id, owner, title, source, mesh_params, created_ms, "
                        "modified_ms) VALUES('old', 'alice', 'v1 case', 'phantom:abdomen', x'00', "
                        "1, 2); INSERT INTO events VALUES('old', 1, 0, 1, 2, 3, 0, 0, 0, 0, 5);",
                        "write a version-1 case")
                    .ok());
  }
  auto store = Open();
  ASSERT_TRUE(store);
  auto record = store->Get("old");
  ASSERT_TRUE(record.ok()) << record.status();
  EXPECT_EQ(record->title, "v1 case");
  EXPECT_EQ(record->notes, "");  // added by migration 2
  EXPECT_EQ(record->events, 1);
  ASSERT_TRUE(store->Update("old", std::nullopt, std::string("kept")).ok());
  EXPECT_EQ(store->Get("old")->notes, "kept");
}

TEST_F(CaseStoreTest, ANewerDamagedOrUnwritableDatabaseIsRefusedWithTheReason) {
  {
    sqlite3* raw = nullptr;
    ASSERT_EQ(sqlite3_open(file().c_str(), &raw), SQLITE_OK);
    SqliteDb db(raw);
    ASSERT_TRUE(db.Exec("PRAGMA user_version = 99", "set").ok());
  }
  auto newer = OpenSqliteCaseStore(file());
  EXPECT_EQ(newer.status().code(), absl::StatusCode::kFailedPrecondition);
  EXPECT_NE(newer.status().message().find("newer vpm-server"), std::string::npos)
      << newer.status();

  fs::remove(file());
  std::ofstream(file()) << std::string(8192, 'x');  // not a database
  auto damaged = OpenSqliteCaseStore(file());
  EXPECT_EQ(damaged.status().code(), absl::StatusCode::kDataLoss) << damaged.status();
  EXPECT_NE(damaged.status().message().find("damaged"), std::string::npos) << damaged.status();

  auto nowhere = OpenSqliteCaseStore(dir_ / "missing-folder" / "cases.sqlite");
  EXPECT_FALSE(nowhere.ok());
  EXPECT_NE(nowhere.status().message().find("case store"), std::string::npos);
}

TEST_F(CaseStoreTest, ALockedDatabaseRefusesTheEventAndKeepsWhatItHad) {
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
TEST_F(CaseStoreTest, AFullDiskRefusesTheEventWholeAndTheStoreGoesOnAfterwards) {
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

}  // namespace
}  // namespace vpm::cases
