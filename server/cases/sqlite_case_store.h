// The embedded case store: one SQLite file (vpm-server --state-dir DIR:
// DIR/cases.sqlite) in WAL mode with foreign keys and a busy timeout.
// synchronous=NORMAL: a committed event survives the process being killed
// (kill -9, a crash); a power cut may lose the last ones (docs/CASES.md).
#pragma once

#include <filesystem>
#include <memory>

#include "server/cases/case_store.h"

namespace vpm::cases {

struct SqliteCaseStoreOptions {
  int busy_timeout_ms = 2000;  // waits this long for another writer's lock
};

// Opens (creating) the database at `file`, checks it (quick_check) and
// migrates it to the current schema. The error says what is wrong: not
// writable, damaged, locked, newer than this build.
Result<std::unique_ptr<CaseStore>> OpenSqliteCaseStore(const std::filesystem::path& file,
                                                       const SqliteCaseStoreOptions& options = {});

}  // namespace vpm::cases
