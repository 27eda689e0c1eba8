// SqlConnection over SQLite's C API (sqlite_handle.h), and the SQLite case
// store.
#include <cctype>

#include "server/cases/open_case_store.h"
#include "server/cases/sql_case_store.h"
#include "server/cases/sqlite_handle.h"

namespace vpm::cases {
namespace {

// "$3" -> "?3": SQLite's numbered parameters.
std::string NumberedParameters(std::string_view sql) {
  std::string out(sql);
  for (size_t i = 0; i + 1 < out.size(); ++i) {
    if (out[i] == '$' && std::isdigit(static_cast<unsigned char>(out[i + 1]))) out[i] = '?';
  }
  return out;
}

class SqliteConnection final : public SqlConnection {
 public:
  explicit SqliteConnection(SqliteDb db) : db_(std::move(db)) {}
  SqlDialect dialect() const override { return SqlDialect::kSqlite; }

  Result<std::vector<SqlRow>> Query(std::string_view sql, const std::vector<SqlValue>& params,
                                    std::string_view what) override {
    ASSIGN_OR_RETURN(SqliteStatement statement,
                     SqliteStatement::Prepare(db_, NumberedParameters(sql)));
    for (size_t i = 0; i < params.size(); ++i) {
      const int at = static_cast<int>(i + 1);
      const SqlValue& p = params[i];
      if (const auto* n = std::get_if<int64_t>(&p)) statement.Bind(at, *n);
      if (const auto* d = std::get_if<double>(&p)) statement.Bind(at, *d);
      if (const auto* s = std::get_if<std::string>(&p)) statement.Bind(at, std::string_view(*s));
      if (const auto* b = std::get_if<SqlBlob>(&p)) statement.BindBlob(at, b->bytes);
    }
    std::vector<SqlRow> rows;
    for (;;) {
      ASSIGN_OR_RETURN(const bool row, statement.Step(what));
      if (!row) return rows;
      rows.push_back(statement.Row());
    }
  }

  Status ExecScript(const std::string& sql, std::string_view what) override {
    return db_.Exec(sql, what);
  }
  Status Begin(std::string_view what) override {
    return db_.Exec("BEGIN IMMEDIATE", StrCat("start to ", what));
  }
  Status Commit(std::string_view what) override { return db_.Exec("COMMIT", what); }
  void Rollback() override { db_.Exec("ROLLBACK", "roll back").IgnoreError(); }
  Status LockSchema() override { return absl::OkStatus(); }
  Result<int> SchemaVersion() override {
    ASSIGN_OR_RETURN(std::vector<SqlRow> rows,
                     Query("PRAGMA user_version", {}, "read the schema version"));
    return rows.empty() ? 0 : static_cast<int>(SqlInt(rows[0][0]));
  }
  std::string SetSchemaVersionSql(int version) const override {
    return StrCat("PRAGMA user_version = ", version, ";");
  }
  std::string_view LockRowSuffix() const override { return ""; }
  const SqliteDb& db() const { return db_; }

 private:
  SqliteDb db_;
};

Status Configure(SqliteConnection& connection, const SqliteCaseStoreOptions& options) {
  sqlite3_busy_timeout(connection.db().get(), options.busy_timeout_ms);
  ASSIGN_OR_RETURN(std::vector<SqlRow> wal,
                   connection.Query("PRAGMA journal_mode=WAL", {}, "turn on write-ahead logging"));
  if (wal.empty() || SqlText(wal[0][0]) != "wal") {
    return absl::FailedPreconditionError(
        "case store: the state directory's file system does not support SQLite's write-ahead "
        "log (WAL); use a local disk");
  }
  RETURN_IF_ERROR(connection.ExecScript("PRAGMA synchronous=NORMAL; PRAGMA foreign_keys=ON;",
                                        "configure the database"));
  ASSIGN_OR_RETURN(std::vector<SqlRow> check,
                   connection.Query("PRAGMA quick_check", {}, "check the database"));
  if (check.empty() || SqlText(check[0][0]) != "ok") {
    return absl::DataLossError(StrCat("case store: the database file is damaged (",
                                      check.empty() ? "no answer" : SqlText(check[0][0]),
                                      "); restore it from a backup"));
  }
  return absl::OkStatus();
}

}  // namespace

Result<std::unique_ptr<SqlConnection>> OpenSqliteConnection(
    const std::filesystem::path& file, const SqliteCaseStoreOptions& options) {
  sqlite3* raw = nullptr;
  const int rc = sqlite3_open_v2(file.c_str(), &raw, SQLITE_OPEN_READWRITE | SQLITE_OPEN_CREATE,
                                 nullptr);
  SqliteDb db(raw);
  if (rc != SQLITE_OK) {
    return SqliteError(rc, StrCat("open ", file.string()),
                       raw != nullptr ? sqlite3_errmsg(raw) : sqlite3_errstr(rc));
  }
  sqlite3_extended_result_codes(db.get(), 1);
  auto connection = std::make_unique<SqliteConnection>(std::move(db));
  RETURN_IF_ERROR(Configure(*connection, options));
  return std::unique_ptr<SqlConnection>(std::move(connection));
}

Result<std::unique_ptr<CaseStore>> OpenSqliteCaseStore(const std::filesystem::path& file,
                                                       const SqliteCaseStoreOptions& options) {
  ASSIGN_OR_RETURN(std::unique_ptr<SqlConnection> connection, OpenSqliteConnection(file, options));
  return MakeSqlCaseStore(std::move(connection));
}

}  // namespace vpm::cases
