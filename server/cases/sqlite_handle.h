// RAII for SQLite's C API: a connection and a prepared statement, and the
// mapping of SQLite's result codes onto the project's errors.
#pragma once

#include <sqlite3.h>

#include <cstdint>
#include <filesystem>
#include <memory>
#include <string>
#include <string_view>

#include "server/cases/sql_connection.h"
#include "server/common/status.h"

namespace vpm::cases {

// `what` names the operation ("append an event"); the message says what
// went wrong in the user's words and SQLite's.
Status SqliteError(int code, std::string_view what, std::string_view detail);

class SqliteDb {
 public:
  SqliteDb() = default;
  explicit SqliteDb(sqlite3* db) : db_(db) {}
  SqliteDb(SqliteDb&& other) noexcept : db_(other.db_) { other.db_ = nullptr; }
  SqliteDb& operator=(SqliteDb&& other) noexcept;
  SqliteDb(const SqliteDb&) = delete;
  SqliteDb& operator=(const SqliteDb&) = delete;
  ~SqliteDb();
  sqlite3* get() const { return db_; }
  // Runs statements without results (sqlite3_exec).
  Status Exec(const std::string& sql, std::string_view what) const;

 private:
  sqlite3* db_ = nullptr;
};

class SqliteStatement {
 public:
  static Result<SqliteStatement> Prepare(const SqliteDb& db, std::string_view sql);
  SqliteStatement(SqliteStatement&& other) noexcept : db_(other.db_), stmt_(other.stmt_) {
    other.stmt_ = nullptr;
  }
  SqliteStatement(const SqliteStatement&) = delete;
  SqliteStatement& operator=(const SqliteStatement&) = delete;
  SqliteStatement& operator=(SqliteStatement&&) = delete;
  ~SqliteStatement();

  // Parameters count from 1, as SQLite's do.
  SqliteStatement& Bind(int index, std::string_view text);
  SqliteStatement& BindBlob(int index, std::string_view bytes);
  SqliteStatement& Bind(int index, int64_t value);
  SqliteStatement& Bind(int index, double value);
  // True with a row to read, false when done.
  Result<bool> Step(std::string_view what);
  // Steps to the end (a statement without rows).
  Status Run(std::string_view what);
  std::string Text(int column) const;
  int64_t Int(int column) const;
  double Real(int column) const;
  // The current row, each column as SQLite typed it.
  SqlRow Row() const;

 private:
  SqliteStatement(sqlite3* db, sqlite3_stmt* stmt) : db_(db), stmt_(stmt) {}
  sqlite3* db_;
  sqlite3_stmt* stmt_;
};

struct SqliteCaseStoreOptions;
// An open, configured connection (WAL, synchronous=NORMAL, foreign keys, the
// busy timeout, quick_check); the SQLite case store runs over it.
Result<std::unique_ptr<SqlConnection>> OpenSqliteConnection(const std::filesystem::path& file,
                                                            const SqliteCaseStoreOptions& options);

}  // namespace vpm::cases
