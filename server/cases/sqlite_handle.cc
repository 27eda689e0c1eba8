#include "server/cases/sqlite_handle.h"

namespace vpm::cases {

Status SqliteError(int code, std::string_view what, std::string_view detail) {
  const std::string context = StrCat("case store: could not ", what, " (SQLite: ", detail, ")");
  switch (code & 0xff) {
    case SQLITE_FULL:
      return absl::ResourceExhaustedError(
          StrCat(context, ": the disk holding the state directory is full; free space, then retry"));
    case SQLITE_IOERR:
      return absl::ResourceExhaustedError(
          StrCat(context, ": the state directory could not be written (a full disk or a file "
                          "size limit); free space, then retry"));
    case SQLITE_BUSY:
    case SQLITE_LOCKED:
      return absl::UnavailableError(
          StrCat(context, ": the database is locked by another process; retry"));
    case SQLITE_CORRUPT:
    case SQLITE_NOTADB:
      return absl::DataLossError(
          StrCat(context, ": the database file is damaged; restore it from a backup"));
    case SQLITE_READONLY:
    case SQLITE_PERM:
    case SQLITE_CANTOPEN:
      return absl::FailedPreconditionError(
          StrCat(context, ": the state directory is not writable by this process"));
    case SQLITE_CONSTRAINT:
      return absl::AlreadyExistsError(context);
    default:
      return absl::InternalError(context);
  }
}

SqliteDb& SqliteDb::operator=(SqliteDb&& other) noexcept {
  if (this != &other) {
    if (db_ != nullptr) sqlite3_close_v2(db_);
    db_ = other.db_;
    other.db_ = nullptr;
  }
  return *this;
}

SqliteDb::~SqliteDb() {
  if (db_ != nullptr) sqlite3_close_v2(db_);
}

Status SqliteDb::Exec(const std::string& sql, std::string_view what) const {
  char* message = nullptr;
  const int rc = sqlite3_exec(db_, sql.c_str(), nullptr, nullptr, &message);
  if (rc == SQLITE_OK) return absl::OkStatus();
  const std::string detail = message != nullptr ? message : sqlite3_errstr(rc);
  sqlite3_free(message);
  return SqliteError(sqlite3_extended_errcode(db_), what, detail);
}

Result<SqliteStatement> SqliteStatement::Prepare(const SqliteDb& db, std::string_view sql) {
  sqlite3_stmt* stmt = nullptr;
  const int rc = sqlite3_prepare_v2(db.get(), sql.data(), static_cast<int>(sql.size()), &stmt,
                                    nullptr);
  if (rc != SQLITE_OK) {
    return SqliteError(rc, "prepare a statement", sqlite3_errmsg(db.get()));
  }
  return SqliteStatement(db.get(), stmt);
}

SqliteStatement::~SqliteStatement() {
  if (stmt_ != nullptr) sqlite3_finalize(stmt_);
}

SqliteStatement& SqliteStatement::Bind(int index, std::string_view text) {
  sqlite3_bind_text(stmt_, index, text.data(), static_cast<int>(text.size()), SQLITE_TRANSIENT);
  return *this;
}

SqliteStatement& SqliteStatement::BindBlob(int index, std::string_view bytes) {
  sqlite3_bind_blob(stmt_, index, bytes.data(), static_cast<int>(bytes.size()), SQLITE_TRANSIENT);
  return *this;
}

SqliteStatement& SqliteStatement::Bind(int index, int64_t value) {
  sqlite3_bind_int64(stmt_, index, value);
  return *this;
}

SqliteStatement& SqliteStatement::Bind(int index, double value) {
  sqlite3_bind_double(stmt_, index, value);
  return *this;
}

Result<bool> SqliteStatement::Step(std::string_view what) {
  const int rc = sqlite3_step(stmt_);
  if (rc == SQLITE_ROW) return true;
  if (rc == SQLITE_DONE) return false;
  return SqliteError(sqlite3_extended_errcode(db_), what, sqlite3_errmsg(db_));
}

Status SqliteStatement::Run(std::string_view what) {
  for (;;) {
    ASSIGN_OR_RETURN(const bool row, Step(what));
    if (!row) return absl::OkStatus();
  }
}

std::string SqliteStatement::Text(int column) const {
  const void* bytes = sqlite3_column_blob(stmt_, column);
  const int n = sqlite3_column_bytes(stmt_, column);
  return bytes == nullptr ? std::string() : std::string(static_cast<const char*>(bytes), n);
}

int64_t SqliteStatement::Int(int column) const { return sqlite3_column_int64(stmt_, column); }

double SqliteStatement::Real(int column) const { return sqlite3_column_double(stmt_, column); }

SqlRow SqliteStatement::Row() const {
  SqlRow row;
  const int n = sqlite3_column_count(stmt_);
  row.reserve(n);
  for (int c = 0; c < n; ++c) {
    switch (sqlite3_column_type(stmt_, c)) {
      case SQLITE_INTEGER: row.emplace_back(Int(c)); break;
      case SQLITE_FLOAT: row.emplace_back(Real(c)); break;
      case SQLITE_TEXT: row.emplace_back(Text(c)); break;
      case SQLITE_BLOB: row.emplace_back(SqlBlob{Text(c)}); break;
      default: row.emplace_back(std::monostate{}); break;
    }
  }
  return row;
}

}  // namespace vpm::cases
