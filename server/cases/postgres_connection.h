// An open PostgreSQL connection (libpq) for the case store; the store
// itself: open_case_store.h. Refuses a connection string with a password.
#pragma once

#include <memory>
#include <string>

#include "server/cases/sql_connection.h"

namespace vpm::cases {

Result<std::unique_ptr<SqlConnection>> OpenPostgresConnection(const std::string& conninfo);

}  // namespace vpm::cases
