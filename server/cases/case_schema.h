// The case database's schema, versioned: migration i takes a database at
// version i to i + 1, in one transaction, in each dialect's own types
// (SQLite: INTEGER, REAL, BLOB; PostgreSQL: BIGINT, DOUBLE PRECISION,
// BYTEA). A database written by a newer vpm is refused, never downgraded.
#pragma once

#include <string>
#include <vector>

#include "server/cases/sql_connection.h"

namespace vpm::cases {

inline constexpr int kCaseSchemaVersion = 4;

// The SQL of each migration in `dialect`: [0] creates version 1, [1] takes
// it to 2, ...
const std::vector<std::string>& CaseSchemaMigrations(SqlDialect dialect);

// Brings the database to version `target` (<= kCaseSchemaVersion), in one
// transaction with the schema locked.
// FailedPrecondition when it is newer than this build knows.
Status MigrateCaseSchema(SqlConnection& db, int target = kCaseSchemaVersion);

}  // namespace vpm::cases
