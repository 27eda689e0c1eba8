// One database connection as the case store uses it: parameterised
// statements ($1, $2, ... in the SQL) returning rows of values, and
// transactions. SQLite (sqlite_connection.h) and PostgreSQL
// (postgres_connection.h) implement it; SqlCaseStore holds the case logic
// once for both. Not thread-safe: the store serialises its calls.
#pragma once

#include <cstdint>
#include <string>
#include <string_view>
#include <variant>
#include <vector>

#include "server/common/status.h"

namespace vpm::cases {

// A blob is bytes (BLOB, BYTEA); text is UTF-8 (TEXT).
struct SqlBlob {
  std::string bytes;
};
using SqlValue = std::variant<std::monostate, int64_t, double, std::string, SqlBlob>;
using SqlRow = std::vector<SqlValue>;

// Readers of a column as the store declared it (NULL reads as 0 or "").
int64_t SqlInt(const SqlValue& value);
double SqlReal(const SqlValue& value);
std::string SqlText(const SqlValue& value);  // text or blob bytes

enum class SqlDialect { kSqlite, kPostgres };

class SqlConnection {
 public:
  virtual ~SqlConnection() = default;
  virtual SqlDialect dialect() const = 0;
  // Runs `sql` (one statement) with `params` bound to $1.., returning its
  // rows. `what` names the operation for the error ("store an event").
  virtual Result<std::vector<SqlRow>> Query(std::string_view sql,
                                            const std::vector<SqlValue>& params,
                                            std::string_view what) = 0;
  // Several statements without parameters or rows (migrations).
  virtual Status ExecScript(const std::string& sql, std::string_view what) = 0;
  // A write transaction: SQLite takes the write lock at once (BEGIN
  // IMMEDIATE); PostgreSQL begins, and rows are locked with FOR UPDATE.
  virtual Status Begin(std::string_view what) = 0;
  virtual Status Commit(std::string_view what) = 0;
  virtual void Rollback() = 0;
  // Inside a transaction: waits for any other process migrating the same
  // database (SQLite: BEGIN IMMEDIATE already holds the write lock).
  virtual Status LockSchema() = 0;
  // The schema version stored in the database (0: none yet), and the
  // statement that sets it (run inside a migration's transaction).
  virtual Result<int> SchemaVersion() = 0;
  virtual std::string SetSchemaVersionSql(int version) const = 0;
  // Appended to a SELECT that must lock its row until commit.
  virtual std::string_view LockRowSuffix() const = 0;
};

}  // namespace vpm::cases
