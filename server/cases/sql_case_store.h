// The case store's logic over one SQL connection (sql_connection.h): the
// same statements on SQLite and PostgreSQL, each call one transaction,
// serialised by a mutex (one connection per store).
#pragma once

#include <memory>

#include "server/cases/case_store.h"
#include "server/cases/sql_connection.h"

namespace vpm::cases {

// Migrates the connection's database to the current schema
// (case_schema.h) and returns the store over it.
Result<std::unique_ptr<CaseStore>> MakeSqlCaseStore(std::unique_ptr<SqlConnection> connection);

}  // namespace vpm::cases
