// The case store's event writes, as a session makes them: per Append
// (one transaction, committed), p50 / p99 / max in ms, on SQLite (a file
// in a temporary folder) and, with --postgres CONNINFO, on PostgreSQL; and
// the database's size per case. Each case is a drag session: a grab, 60
// drag events, a kept release, over and over. Then 100 view writes per case
// (SetRenderSettings), as sessions store a changed view with a still.
//
//   build/bench/case_store_bench [--cases 10] [--events 600] [--postgres CONNINFO]
//   (make bench starts a throwaway PostgreSQL for it: scripts/bench.sh)
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <string>
#include <vector>

#include "bench/bench_util.h"
#include "server/cases/open_case_store.h"
#include "server/cases/postgres_connection.h"

namespace vpm::bench {
namespace {

namespace fs = std::filesystem;
using cases::CaseStore;

struct Figures {
  double p50_ms = 0, p99_ms = 0, max_ms = 0;
  int64_t events = 0;
};

SceneOp OpAt(int i) {
  const int k = i % 62;
  if (k == 0) return {.kind = SceneOp::Kind::kGrab, .grab = {.point_mm = {100, 120, 80 + i % 7}}};
  if (k == 61) return {.kind = SceneOp::Kind::kRelease, .keep = true};
  return {.kind = SceneOp::Kind::kDrag, .vector = {0.1 * k, 0.05 * k, -0.2 * k}};
}

Figures Run(CaseStore& store, int cases, int events) {
  std::vector<double> ms;
  ms.reserve(size_t(cases) * events);
  for (int c = 0; c < cases; ++c) {
    const std::string id = "bench-case-" + std::to_string(c);
    Check(absl::StatusOr<bool>(store.Create({.id = id, .owner = "alice", .source = "phantom:abdomen",
                                             .mesh_params = std::string(96, 'p')})
                                   .ok()),
          "create");
    for (int i = 0; i < events; ++i) {
      const auto t0 = std::chrono::steady_clock::now();
      Check(store.Append(id, OpAt(i), 0.01 * i), "append");
      ms.push_back(MsSince(t0));
    }
  }
  std::sort(ms.begin(), ms.end());
  auto at = [&](double q) { return ms[std::min(ms.size() - 1, size_t(q * ms.size()))]; };
  return {at(0.50), at(0.99), ms.back(), int64_t(ms.size())};
}

// View writes (SetRenderSettings, one UPDATE of the case's row): what a
// session stores with a still after its client changed the view. `bytes`:
// a serialized RenderSettings of a crop box, a clip plane and two slices is
// about 200 bytes; two alternate so that every write changes the row.
Figures RunViews(CaseStore& store, int cases, int writes, size_t bytes) {
  std::vector<double> ms;
  ms.reserve(size_t(cases) * writes);
  const std::string views[2] = {std::string(bytes, 'a'), std::string(bytes, 'b')};
  for (int c = 0; c < cases; ++c) {
    const std::string id = "bench-case-" + std::to_string(c);
    for (int i = 0; i < writes; ++i) {
      const auto t0 = std::chrono::steady_clock::now();
      Check(absl::StatusOr<bool>(store.SetRenderSettings(id, views[i % 2]).ok()), "view");
      ms.push_back(MsSince(t0));
    }
  }
  std::sort(ms.begin(), ms.end());
  auto at = [&](double q) { return ms[std::min(ms.size() - 1, size_t(q * ms.size()))]; };
  return {at(0.50), at(0.99), ms.back(), int64_t(ms.size())};
}

void ViewRow(const char* backend, const Figures& f) {
  std::printf("| %-10s | %7lld | %8.3f | %8.3f | %8.3f |   (view writes, 200 bytes)\n", backend,
              static_cast<long long>(f.events), f.p50_ms, f.p99_ms, f.max_ms);
}

uintmax_t SqliteBytes(const fs::path& dir) {
  uintmax_t total = 0;
  for (const auto& entry : fs::directory_iterator(dir)) total += entry.file_size();
  return total;
}

void Row(const char* backend, const Figures& f, double bytes_per_case, int events) {
  std::printf("| %-10s | %7lld | %8.3f | %8.3f | %8.3f | %10.0f | %9.0f |\n", backend,
              static_cast<long long>(f.events), f.p50_ms, f.p99_ms, f.max_ms, bytes_per_case,
              bytes_per_case / events);
}

}  // namespace
}  // namespace vpm::bench

int main(int argc, char** argv) {
  using namespace vpm;
  using namespace vpm::bench;
  int cases = 10, events = 600;
  std::string postgres;
  for (int i = 1; i + 1 < argc; i += 2) {
    if (!std::strcmp(argv[i], "--cases")) cases = std::atoi(argv[i + 1]);
    else if (!std::strcmp(argv[i], "--events")) events = std::atoi(argv[i + 1]);
    else if (!std::strcmp(argv[i], "--postgres")) postgres = argv[i + 1];
  }
  if (cases < 1 || events < 1) {
    std::fprintf(stderr, "usage: case_store_bench [--cases N] [--events N] [--postgres CONNINFO]\n");
    return 2;
  }
  std::printf("Case event writes (Append: one committed transaction each), %d cases x %d "
              "events\n\n",
              cases, events);
  std::printf("| backend    |  events |  p50 ms  |  p99 ms  |  max ms  | bytes/case | bytes/event |\n");
  std::printf("|------------|---------|----------|----------|----------|------------|-------------|\n");
  const fs::path dir = fs::temp_directory_path() / ("vpm-case-bench-" + std::to_string(getpid()));
  fs::create_directories(dir);
  {
    auto store = Check(cases::OpenSqliteCaseStore(dir / "cases.sqlite"), "open SQLite");
    const Figures f = Run(*store, cases, events);
    const Figures views = RunViews(*store, cases, 100, 200);
    store.reset();  // closing checkpoints the WAL into the file
    Row("SQLite", f, double(SqliteBytes(dir)) / cases, events);
    ViewRow("SQLite", views);
  }
  fs::remove_all(dir);
  if (!postgres.empty()) {
    auto db = Check(cases::OpenPostgresConnection(postgres), "connect to PostgreSQL");
    Check(absl::StatusOr<bool>(db->ExecScript("DROP TABLE IF EXISTS events, case_shares, cases, "
                                              "vpm_schema_version CASCADE",
                                              "empty")
                                   .ok()),
          "empty the database");
    auto store = Check(cases::OpenPostgresCaseStore(postgres), "open PostgreSQL");
    const Figures f = Run(*store, cases, events);
    const Figures views = RunViews(*store, cases, 100, 200);
    auto size = Check(db->Query("SELECT pg_total_relation_size('events') + "
                                "pg_total_relation_size('cases') + "
                                "pg_total_relation_size('case_shares')",
                                {}, "size"),
                      "size");
    Row("PostgreSQL", f, double(cases::SqlInt(size[0][0])) / cases, events);
    ViewRow("PostgreSQL", views);
  } else {
    std::printf("| PostgreSQL | (not run: --postgres CONNINFO)                                      |\n");
  }
  return 0;
}
