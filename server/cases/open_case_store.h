// The case stores vpm-server can open (docs/CASES.md): the embedded SQLite
// file of --state-dir, or a PostgreSQL database shared by replicas
// (--state postgresql://...). Each checks the database and migrates it to
// the current schema; the error says what is wrong (not writable, damaged,
// locked, unreachable, newer than this build).
#pragma once

#include <filesystem>
#include <memory>
#include <string>

#include "server/cases/case_store.h"

namespace vpm::cases {

struct SqliteCaseStoreOptions {
  int busy_timeout_ms = 2000;  // waits this long for another writer's lock
};

// One SQLite file in WAL mode with foreign keys and a busy timeout.
// synchronous=NORMAL: a committed event survives the process being killed
// (kill -9, a crash); a power cut may lose the last ones.
Result<std::unique_ptr<CaseStore>> OpenSqliteCaseStore(const std::filesystem::path& file,
                                                       const SqliteCaseStoreOptions& options = {});

// A PostgreSQL connection string (libpq: a postgresql:// URI or key=value
// pairs). A password in it is refused: libpq reads it from its password
// file (PGPASSFILE, ~/.pgpass), so that it is never in argv or a log.
Result<std::unique_ptr<CaseStore>> OpenPostgresCaseStore(const std::string& conninfo);

}  // namespace vpm::cases
