// The case database's schema, versioned (PRAGMA user_version): migration i
// takes a database at version i to i + 1, in one transaction. A database
// written by a newer vpm is refused, never downgraded.
#pragma once

#include <string>
#include <vector>

#include "server/cases/sqlite_handle.h"

namespace vpm::cases {

inline constexpr int kCaseSchemaVersion = 2;

// The SQL of each migration: [0] creates version 1, [1] takes it to 2, ...
const std::vector<std::string>& CaseSchemaMigrations();

// Brings `db` to version `target` (<= kCaseSchemaVersion). FailedPrecondition
// when the database is newer than this build knows.
Status MigrateCaseSchema(const SqliteDb& db, int target = kCaseSchemaVersion);

// The database's schema version (0: empty).
Result<int> CaseSchemaVersion(const SqliteDb& db);

}  // namespace vpm::cases
