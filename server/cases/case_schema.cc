#include "server/cases/case_schema.h"

namespace vpm::cases {

const std::vector<std::string>& CaseSchemaMigrations() {
  static const std::vector<std::string> migrations = {
      // 1: cases, their shares and their events. Events are kept per case
      // in order (seq from 1); an undone event stays until a new one
      // replaces it (redo).
      R"sql(
CREATE TABLE cases(
  id TEXT PRIMARY KEY,
  owner TEXT NOT NULL,
  title TEXT NOT NULL DEFAULT '',
  source TEXT NOT NULL,
  mesh_params BLOB NOT NULL,
  camera BLOB NOT NULL DEFAULT x'',
  created_ms INTEGER NOT NULL,
  modified_ms INTEGER NOT NULL);
CREATE INDEX cases_by_owner ON cases(owner);
CREATE TABLE case_shares(
  case_id TEXT NOT NULL REFERENCES cases(id) ON DELETE CASCADE,
  user TEXT NOT NULL,
  PRIMARY KEY(case_id, user)) WITHOUT ROWID;
CREATE INDEX case_shares_by_user ON case_shares(user);
CREATE TABLE events(
  case_id TEXT NOT NULL REFERENCES cases(id) ON DELETE CASCADE,
  seq INTEGER NOT NULL,
  kind INTEGER NOT NULL,
  x REAL NOT NULL, y REAL NOT NULL, z REAL NOT NULL,
  rule INTEGER NOT NULL,
  radius_mm REAL NOT NULL,
  keep INTEGER NOT NULL,
  undone INTEGER NOT NULL DEFAULT 0,
  time_ms INTEGER NOT NULL,
  PRIMARY KEY(case_id, seq)) WITHOUT ROWID;
)sql",
      // 2: a case's notes, and the largest displacement its last event left
      // (case list and show report it without a replay).
      R"sql(
ALTER TABLE cases ADD COLUMN notes TEXT NOT NULL DEFAULT '';
ALTER TABLE cases ADD COLUMN max_displacement_mm REAL NOT NULL DEFAULT 0;
)sql",
  };
  return migrations;
}

Result<int> CaseSchemaVersion(const SqliteDb& db) {
  ASSIGN_OR_RETURN(SqliteStatement query, SqliteStatement::Prepare(db, "PRAGMA user_version"));
  ASSIGN_OR_RETURN(const bool row, query.Step("read the schema version"));
  return row ? static_cast<int>(query.Int(0)) : 0;
}

Status MigrateCaseSchema(const SqliteDb& db, int target) {
  ASSIGN_OR_RETURN(const int version, CaseSchemaVersion(db));
  if (version > kCaseSchemaVersion) {
    return absl::FailedPreconditionError(
        StrCat("case store: the database is at schema version ", version,
               ", written by a newer vpm-server (this one knows up to ", kCaseSchemaVersion,
               "); run that version, or restore a backup"));
  }
  const auto& migrations = CaseSchemaMigrations();
  for (int v = version; v < target; ++v) {
    const std::string sql = StrCat("BEGIN IMMEDIATE;", migrations[v],
                                   "PRAGMA user_version = ", v + 1, ";COMMIT;");
    if (Status status = db.Exec(sql, StrCat("migrate the schema to version ", v + 1));
        !status.ok()) {
      db.Exec("ROLLBACK", "roll back a migration").IgnoreError();
      return status;
    }
  }
  return absl::OkStatus();
}

}  // namespace vpm::cases
