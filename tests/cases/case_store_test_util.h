// The case store tests' fixture: a fresh database of either backend.
// SQLite: a file in a temporary folder. PostgreSQL: the server that
// scripts/pg-test-server.sh started for ctest (its connection string in the
// file VPM_TEST_POSTGRES names), a database of its own for each test, so that
// tests run in parallel (ctest -j) never touch each other's tables.
#pragma once

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <string>

#include "server/cases/open_case_store.h"
#include "server/cases/postgres_connection.h"
#include "server/cases/sqlite_handle.h"

namespace vpm::cases {

// A case and ops the tests store.
inline CaseRecord Record(const std::string& id, const std::string& owner) {
  return {.id = id, .owner = owner, .title = "left kidney", .source = "ct/abdomen.nii.gz",
          .mesh_params = std::string("\x10\x20\0\xff", 4)};
}
inline SceneOp Grab(double x) {
  return {.kind = SceneOp::Kind::kGrab, .grab = {.point_mm = {x, 2.0, 3.0}, .radius_mm = 4.5}};
}
inline SceneOp Drag(double z) { return {.kind = SceneOp::Kind::kDrag, .vector = {0, 0, z}}; }
inline SceneOp Release(bool keep) { return {.kind = SceneOp::Kind::kRelease, .keep = keep}; }

enum class Backend { kSqlite, kPostgres };

inline std::string BackendName(const ::testing::TestParamInfo<Backend>& info) {
  return info.param == Backend::kSqlite ? "Sqlite" : "Postgres";
}

class CaseStoreFixture : public ::testing::TestWithParam<Backend> {
 protected:
  void SetUp() override {
    dir_ = std::filesystem::temp_directory_path() /
           ("vpm-case-store-" + std::to_string(::getpid()) + "-" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    std::filesystem::remove_all(dir_);
    std::filesystem::create_directories(dir_);
    if (GetParam() == Backend::kPostgres) {
      const char* file = std::getenv("VPM_TEST_POSTGRES");
      ASSERT_NE(file, nullptr) << "VPM_TEST_POSTGRES is not set: run under ctest, which starts "
                                  "PostgreSQL (scripts/pg-test-server.sh)";
      std::ifstream in(file);
      std::string server;
      ASSERT_TRUE(std::getline(in, server)) << "no connection string in " << file;
      auto admin = OpenPostgresConnection(server);
      ASSERT_TRUE(admin.ok()) << admin.status();
      database_ = "vpm_test_" + std::to_string(::getpid()) + "_" +
                  std::to_string(::testing::UnitTest::GetInstance()->random_seed()) + "_" +
                  std::to_string(++databases_made_);
      ASSERT_TRUE((*admin)->ExecScript("DROP DATABASE IF EXISTS " + database_, "drop").ok());
      ASSERT_TRUE((*admin)->ExecScript("CREATE DATABASE " + database_, "create").ok());
      admin_ = std::move(*admin);
      conninfo_ = server + " dbname=" + database_;  // libpq: the last dbname wins
    }
  }
  void TearDown() override {
    std::filesystem::remove_all(dir_);
    // The test's stores are closed by now; WITH (FORCE) ends any connection
    // a failed test left open.
    if (admin_) (void)admin_->ExecScript("DROP DATABASE IF EXISTS " + database_ + " WITH (FORCE)", "drop");
  }

  std::filesystem::path file() const { return dir_ / "cases.sqlite"; }
  Result<std::unique_ptr<CaseStore>> TryOpen() {
    return GetParam() == Backend::kSqlite ? OpenSqliteCaseStore(file())
                                          : OpenPostgresCaseStore(conninfo_);
  }
  std::unique_ptr<CaseStore> Open() {
    auto store = TryOpen();
    EXPECT_TRUE(store.ok()) << store.status();
    return store.ok() ? std::move(*store) : nullptr;
  }
  // A connection of the backend's own, beside the store's.
  std::unique_ptr<SqlConnection> Connection() {
    auto db = GetParam() == Backend::kSqlite ? OpenSqliteConnection(file(), {})
                                             : OpenPostgresConnection(conninfo_);
    EXPECT_TRUE(db.ok()) << db.status();
    return db.ok() ? std::move(*db) : nullptr;
  }
  int64_t Count(const std::string& sql) {
    auto db = Connection();
    auto rows = db->Query(sql, {}, "count");
    EXPECT_TRUE(rows.ok()) << rows.status();
    return rows.ok() && !rows->empty() ? SqlInt((*rows)[0][0]) : -1;
  }

  std::filesystem::path dir_;
  std::string conninfo_;
  std::string database_;
  std::unique_ptr<SqlConnection> admin_;
  static inline int databases_made_ = 0;
};

}  // namespace vpm::cases
