#include "server/cases/case_schema.h"

namespace vpm::cases {
namespace {

// Version 1 with the dialect's names for an integer, a float and bytes.
std::string VersionOne(std::string_view integer, std::string_view real, std::string_view bytes,
                       std::string_view no_rowid) {
  // Cases, their shares and their events. Events are kept per case in
  // order (seq from 1); an undone event stays until a new one replaces it.
  return StrCat(R"sql(
CREATE TABLE cases(
  id TEXT PRIMARY KEY,
  owner TEXT NOT NULL,
  title TEXT NOT NULL DEFAULT '',
  source TEXT NOT NULL,
  mesh_params )sql", bytes, R"sql( NOT NULL,
  camera )sql", bytes, R"sql( NOT NULL,
  created_ms )sql", integer, R"sql( NOT NULL,
  modified_ms )sql", integer, R"sql( NOT NULL);
CREATE INDEX cases_by_owner ON cases(owner);
CREATE TABLE case_shares(
  case_id TEXT NOT NULL REFERENCES cases(id) ON DELETE CASCADE,
  user_name TEXT NOT NULL,
  PRIMARY KEY(case_id, user_name)))sql", no_rowid, R"sql(;
CREATE INDEX case_shares_by_user ON case_shares(user_name);
CREATE TABLE events(
  case_id TEXT NOT NULL REFERENCES cases(id) ON DELETE CASCADE,
  seq )sql", integer, R"sql( NOT NULL,
  kind )sql", integer, R"sql( NOT NULL,
  x )sql", real, R"sql( NOT NULL, y )sql", real, R"sql( NOT NULL, z )sql", real, R"sql( NOT NULL,
  rule )sql", integer, R"sql( NOT NULL,
  radius_mm )sql", real, R"sql( NOT NULL,
  keep )sql", integer, R"sql( NOT NULL,
  undone )sql", integer, R"sql( NOT NULL DEFAULT 0,
  time_ms )sql", integer, R"sql( NOT NULL,
  PRIMARY KEY(case_id, seq)))sql", no_rowid, ";\n");
}

// Version 2: a case's notes, and the largest displacement its last event
// left (case list and show report it without a replay).
std::string VersionTwo(std::string_view real) {
  return StrCat("ALTER TABLE cases ADD COLUMN notes TEXT NOT NULL DEFAULT '';\n",
                "ALTER TABLE cases ADD COLUMN max_displacement_mm ", real,
                " NOT NULL DEFAULT 0;\n");
}

// Version 3: an event after which a still frame settled the bounded drag
// (replayed as a settle, so that a reopened case takes the live path).
std::string VersionThree(std::string_view integer) {
  return StrCat("ALTER TABLE events ADD COLUMN settled ", integer, " NOT NULL DEFAULT 0;\n");
}

// Version 4: the render settings a client of its session last set (a
// serialized vpm.v3.RenderSettings without the per-client fields; empty:
// none), so that a case reopens with its preset, crop, clips and slices.
std::string VersionFour(std::string_view bytes, std::string_view empty_bytes) {
  return StrCat("ALTER TABLE cases ADD COLUMN render_settings ", bytes, " NOT NULL DEFAULT ",
                empty_bytes, ";\n");
}

}  // namespace

const std::vector<std::string>& CaseSchemaMigrations(SqlDialect dialect) {
  static const std::vector<std::string> sqlite = {
      VersionOne("INTEGER", "REAL", "BLOB", " WITHOUT ROWID"), VersionTwo("REAL"),
      VersionThree("INTEGER"), VersionFour("BLOB", "x''")};
  static const std::vector<std::string> postgres = {
      VersionOne("BIGINT", "DOUBLE PRECISION", "BYTEA", ""), VersionTwo("DOUBLE PRECISION"),
      VersionThree("BIGINT"), VersionFour("BYTEA", "'\\x'::bytea")};
  return dialect == SqlDialect::kSqlite ? sqlite : postgres;
}

namespace {

Status MigrateLocked(SqlConnection& db, int target) {
  RETURN_IF_ERROR(db.LockSchema());
  ASSIGN_OR_RETURN(const int version, db.SchemaVersion());
  if (version > kCaseSchemaVersion) {
    return absl::FailedPreconditionError(
        StrCat("case store: the database is at schema version ", version,
               ", written by a newer vpm-server (this one knows up to ", kCaseSchemaVersion,
               "); run that version, or restore a backup"));
  }
  const auto& migrations = CaseSchemaMigrations(db.dialect());
  for (int v = version; v < target; ++v) {
    RETURN_IF_ERROR(db.ExecScript(migrations[v] + db.SetSchemaVersionSql(v + 1),
                                  StrCat("migrate the schema to version ", v + 1)));
  }
  return absl::OkStatus();
}

}  // namespace

Status MigrateCaseSchema(SqlConnection& db, int target) {
  // One transaction, the schema locked: replicas starting together migrate
  // once, the others wait and find the work done.
  RETURN_IF_ERROR(db.Begin("migrate the schema"));
  Status status = MigrateLocked(db, target);
  if (status.ok()) status = db.Commit("migrate the schema");
  if (!status.ok()) db.Rollback();
  return status;
}

}  // namespace vpm::cases
