// The case store's contract, on SQLite and on PostgreSQL alike: order across
// a reopen, undo and redo of whole actions, shares, deletion leaving no
// rows, and a database of the previous schema migrated.
#include <cstdio>

#include "server/cases/case_schema.h"
#include "tests/cases/case_store_test_util.h"

namespace vpm::cases {
namespace {

using CaseStoreTest = CaseStoreFixture;

TEST_P(CaseStoreTest, EventsAreKeptInOrderAcrossAReopen) {
  {
    auto store = Open();
    ASSERT_TRUE(store);
    ASSERT_TRUE(store->Create(Record("case-1", "alice")).ok());
    EXPECT_EQ(*store->Append("case-1", Grab(1.0), 0.0), 1);
    EXPECT_EQ(*store->Append("case-1", Drag(5.0 / 3.0), 4.25), 2);
    EXPECT_EQ(*store->Append("case-1", Release(true), 4.0), 3);
    EXPECT_EQ(store->Append("case-9", Grab(1.0), 0.0).status().code(),
              absl::StatusCode::kNotFound);
    EXPECT_EQ(store->Create(Record("case-1", "alice")).code(), absl::StatusCode::kAlreadyExists);
  }
  auto store = Open();
  ASSERT_TRUE(store);
  auto events = store->Events("case-1");
  ASSERT_TRUE(events.ok()) << events.status();
  ASSERT_EQ(events->size(), 3u);
  EXPECT_EQ((*events)[0].op.kind, SceneOp::Kind::kGrab);
  EXPECT_EQ((*events)[0].op.grab.point_mm, glm::dvec3(1.0, 2.0, 3.0));
  EXPECT_EQ((*events)[0].op.grab.radius_mm, 4.5);
  EXPECT_EQ((*events)[1].op.vector, glm::dvec3(0.0, 0.0, 5.0 / 3.0));  // exactly
  EXPECT_TRUE((*events)[2].op.keep);
  auto record = store->Get("case-1");
  ASSERT_TRUE(record.ok());
  EXPECT_EQ(record->events, 3);
  EXPECT_EQ(record->max_displacement_mm, 4.0);
  EXPECT_EQ(record->mesh_params, std::string("\x10\x20\0\xff", 4));  // bytes, not text
  EXPECT_EQ(record->source, "ct/abdomen.nii.gz");
}

TEST_P(CaseStoreTest, UndoTakesBackWholeActionsAndANewEventDropsTheRedo) {
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
  EXPECT_EQ(store->Undo("nope").status().code(), absl::StatusCode::kNotFound);
}

TEST_P(CaseStoreTest, ListsOwnAndSharedCasesAndDeleteRemovesEverything) {
  auto store = Open();
  ASSERT_TRUE(store);
  ASSERT_TRUE(store->Create(Record("a1", "alice")).ok());
  ASSERT_TRUE(store->Create(Record("b1", "bob")).ok());
  ASSERT_TRUE(store->Append("a1", Grab(1), 0).ok());
  ASSERT_TRUE(store->Share("a1", "bob", false).ok());
  ASSERT_TRUE(store->Share("a1", "bob", false).ok());  // twice: still one share
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
  EXPECT_EQ(store->Update("zz", std::string("x"), std::nullopt).code(),
            absl::StatusCode::kNotFound);

  ASSERT_TRUE(store->Share("a1", "carol", false).ok());
  ASSERT_TRUE(store->Delete("a1").ok());
  EXPECT_EQ(store->Get("a1").status().code(), absl::StatusCode::kNotFound);
  EXPECT_EQ(store->Events("a1").status().code(), absl::StatusCode::kNotFound);
  EXPECT_EQ(store->Delete("a1").code(), absl::StatusCode::kNotFound);
  // Nothing of it is left in the database: no events, no shares.
  EXPECT_EQ(Count("SELECT count(*) FROM events WHERE case_id = 'a1'"), 0);
  EXPECT_EQ(Count("SELECT count(*) FROM case_shares WHERE case_id = 'a1'"), 0);
  EXPECT_EQ(Count("SELECT count(*) FROM cases"), 1);
}

TEST_P(CaseStoreTest, ADatabaseOfThePreviousSchemaOpensAfterMigration) {
  {
    auto db = Connection();
    ASSERT_TRUE(db);
    ASSERT_TRUE(MigrateCaseSchema(*db, kCaseSchemaVersion - 1).ok());
    ASSERT_EQ(*db->SchemaVersion(), kCaseSchemaVersion - 1);
    const std::string bytes = GetParam() == Backend::kSqlite ? "x'00'" : "'\\x00'::bytea";
    ASSERT_TRUE(db->ExecScript("INSERT INTO cases(id, owner, title, source, mesh_params, camera, "
                               "created_ms, modified_ms) VALUES('old', 'alice', 'v1 case', "
                               "'phantom:abdomen', " + bytes + ", " + bytes + ", 1, 2); "
                               "INSERT INTO events(case_id, seq, kind, x, y, z, rule, "
                               "radius_mm, keep, undone, time_ms) "
                               "VALUES('old', 1, 0, 1, 2, 3, 0, 0, 0, 0, 5);",
                               "write a case of the previous version")
                    .ok());
  }
  auto store = Open();
  ASSERT_TRUE(store);
  auto record = store->Get("old");
  ASSERT_TRUE(record.ok()) << record.status();
  EXPECT_EQ(record->title, "v1 case");
  EXPECT_EQ(record->notes, "");  // added by migration 2
  EXPECT_EQ(record->events, 1);
  EXPECT_EQ(record->render_settings, "");  // added by migration 4: none kept
  ASSERT_TRUE(store->Update("old", std::nullopt, std::string("kept")).ok());
  EXPECT_EQ(store->Get("old")->notes, "kept");
  ASSERT_TRUE(store->SetRenderSettings("old", std::string("\x12\0\xff", 3)).ok());
  EXPECT_EQ(store->Get("old")->render_settings, std::string("\x12\0\xff", 3));
  EXPECT_EQ(*Connection()->SchemaVersion(), kCaseSchemaVersion);
}

TEST_P(CaseStoreTest, RenderSettingsAreKeptAsBytesAcrossAReopen) {
  const std::string view("\x0a\x03\0mip\xff", 7);  // bytes, not text
  {
    auto store = Open();
    ASSERT_TRUE(store);
    ASSERT_TRUE(store->Create(Record("v", "alice")).ok());
    EXPECT_EQ(store->Get("v")->render_settings, "");
    ASSERT_TRUE(store->SetRenderSettings("v", view).ok());
    EXPECT_EQ(store->SetRenderSettings("nope", view).code(), absl::StatusCode::kNotFound);
  }
  auto store = Open();
  ASSERT_TRUE(store);
  EXPECT_EQ(store->Get("v")->render_settings, view);
  EXPECT_EQ((*store->List("alice"))[0].render_settings, view);
  ASSERT_TRUE(store->SetRenderSettings("v", "").ok());  // none again
  EXPECT_EQ(store->Get("v")->render_settings, "");
}

TEST_P(CaseStoreTest, ANewerSchemaIsRefused) {
  {
    auto store = Open();  // creates the current schema
    ASSERT_TRUE(store);
  }
  auto db = Connection();
  ASSERT_TRUE(db->ExecScript(db->SetSchemaVersionSql(99), "set a newer version").ok());
  auto newer = TryOpen();
  EXPECT_EQ(newer.status().code(), absl::StatusCode::kFailedPrecondition);
  EXPECT_NE(newer.status().message().find("newer vpm-server"), std::string::npos)
      << newer.status();
}

INSTANTIATE_TEST_SUITE_P(Backends, CaseStoreTest,
                         ::testing::Values(Backend::kSqlite, Backend::kPostgres), BackendName);

TEST(PostgresCaseStore, APasswordInTheConnectionStringIsRefusedWithoutEchoingIt) {
  auto store = OpenPostgresCaseStore("postgresql://vpm:hunter2-secret@127.0.0.1/vpm");
  EXPECT_EQ(store.status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_EQ(store.status().message().find("hunter2"), std::string::npos) << store.status();
  auto nowhere = OpenPostgresCaseStore("host=/nonexistent-folder dbname=vpm");
  EXPECT_EQ(nowhere.status().code(), absl::StatusCode::kUnavailable) << nowhere.status();
}

}  // namespace
}  // namespace vpm::cases
