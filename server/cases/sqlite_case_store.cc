#include "server/cases/sqlite_case_store.h"

#include <chrono>
#include <mutex>

#include "server/cases/case_schema.h"
#include "server/cases/sqlite_handle.h"

namespace vpm::cases {
namespace {

int64_t NowMs() {
  return std::chrono::duration_cast<std::chrono::milliseconds>(
             std::chrono::system_clock::now().time_since_epoch())
      .count();
}

Status CaseNotFound(std::string_view id) {
  return absl::NotFoundError(StrCat("case '", id, "' not found"));
}

constexpr std::string_view kCaseColumns =
    "id, owner, title, notes, source, mesh_params, camera, created_ms, modified_ms, "
    "max_displacement_mm, "
    "(SELECT count(*) FROM events e WHERE e.case_id = cases.id AND e.undone = 0), "
    "(SELECT count(*) FROM events e WHERE e.case_id = cases.id AND e.undone = 1)";

class SqliteCaseStore final : public CaseStore {
 public:
  explicit SqliteCaseStore(SqliteDb db) : db_(std::move(db)) {}

  Status Create(const CaseRecord& r) override {
    std::lock_guard lock(mutex_);
    if (r.id.empty() || r.owner.empty() || r.source.empty()) {
      return absl::InvalidArgumentError("case store: a case needs an id, an owner and a source");
    }
    const int64_t now = NowMs();
    ASSIGN_OR_RETURN(SqliteStatement insert,
                     SqliteStatement::Prepare(db_, "INSERT INTO cases(id, owner, title, notes, "
                                                   "source, mesh_params, camera, created_ms, "
                                                   "modified_ms) VALUES(?,?,?,?,?,?,?,?,?)"));
    insert.Bind(1, r.id).Bind(2, r.owner).Bind(3, r.title).Bind(4, r.notes).Bind(5, r.source);
    insert.BindBlob(6, r.mesh_params).BindBlob(7, r.camera).Bind(8, now).Bind(9, now);
    return insert.Run("create a case");
  }

  Result<CaseRecord> Get(std::string_view id) override {
    std::lock_guard lock(mutex_);
    return GetLocked(id);
  }

  Result<std::vector<CaseRecord>> List(std::string_view user) override {
    std::lock_guard lock(mutex_);
    ASSIGN_OR_RETURN(
        SqliteStatement query,
        SqliteStatement::Prepare(
            db_, StrCat("SELECT ", kCaseColumns, " FROM cases WHERE owner = ?1 OR id IN "
                        "(SELECT case_id FROM case_shares WHERE user = ?1) "
                        "ORDER BY modified_ms DESC, id")));
    query.Bind(1, user);
    std::vector<CaseRecord> out;
    for (;;) {
      ASSIGN_OR_RETURN(const bool row, query.Step("list cases"));
      if (!row) break;
      out.push_back(ReadCase(query));
    }
    for (CaseRecord& record : out) {
      ASSIGN_OR_RETURN(record.shared_with, SharesLocked(record.id));
    }
    return out;
  }

  Result<int64_t> Append(std::string_view id, const SceneOp& op,
                         double max_displacement_mm) override {
    std::lock_guard lock(mutex_);
    RETURN_IF_ERROR(db_.Exec("BEGIN IMMEDIATE", "start storing an event"));
    Result<int64_t> seq = AppendLocked(id, op, max_displacement_mm);
    return Finish(std::move(seq), "store an event");
  }

  Result<std::vector<CaseEvent>> Events(std::string_view id) override {
    std::lock_guard lock(mutex_);
    RETURN_IF_ERROR(CheckExistsLocked(id));
    ASSIGN_OR_RETURN(SqliteStatement query,
                     SqliteStatement::Prepare(
                         db_, "SELECT seq, kind, x, y, z, rule, radius_mm, keep, time_ms FROM "
                              "events WHERE case_id = ? AND undone = 0 ORDER BY seq"));
    query.Bind(1, id);
    std::vector<CaseEvent> out;
    for (;;) {
      ASSIGN_OR_RETURN(const bool row, query.Step("read a case's events"));
      if (!row) break;
      out.push_back(ReadEvent(query));
    }
    return out;
  }

  Result<bool> Undo(std::string_view id) override {
    std::lock_guard lock(mutex_);
    RETURN_IF_ERROR(db_.Exec("BEGIN IMMEDIATE", "start an undo"));
    return Finish(UndoLocked(id), "undo");
  }

  Result<bool> Redo(std::string_view id) override {
    std::lock_guard lock(mutex_);
    RETURN_IF_ERROR(db_.Exec("BEGIN IMMEDIATE", "start a redo"));
    return Finish(RedoLocked(id), "redo");
  }

  Status SetCamera(std::string_view id, const std::string& camera) override {
    std::lock_guard lock(mutex_);
    ASSIGN_OR_RETURN(SqliteStatement update,
                     SqliteStatement::Prepare(db_, "UPDATE cases SET camera = ?, modified_ms = ? "
                                                   "WHERE id = ?"));
    update.BindBlob(1, camera).Bind(2, NowMs()).Bind(3, id);
    return RunOnCase(update, id, "store the camera");
  }

  Status SetDisplacement(std::string_view id, double max_displacement_mm) override {
    std::lock_guard lock(mutex_);
    ASSIGN_OR_RETURN(SqliteStatement update,
                     SqliteStatement::Prepare(db_, "UPDATE cases SET max_displacement_mm = ? "
                                                   "WHERE id = ?"));
    update.Bind(1, max_displacement_mm).Bind(2, id);
    return RunOnCase(update, id, "store the displacement");
  }

  Status Update(std::string_view id, const std::optional<std::string>& title,
                const std::optional<std::string>& notes) override {
    std::lock_guard lock(mutex_);
    ASSIGN_OR_RETURN(SqliteStatement update,
                     SqliteStatement::Prepare(
                         db_, "UPDATE cases SET title = coalesce(?, title), notes = "
                              "coalesce(?, notes), modified_ms = ? WHERE id = ?"));
    if (title) update.Bind(1, *title);
    if (notes) update.Bind(2, *notes);
    update.Bind(3, NowMs()).Bind(4, id);
    return RunOnCase(update, id, "rename the case");
  }

  Status Share(std::string_view id, const std::string& user, bool revoke) override {
    std::lock_guard lock(mutex_);
    RETURN_IF_ERROR(CheckExistsLocked(id));
    ASSIGN_OR_RETURN(SqliteStatement change,
                     SqliteStatement::Prepare(
                         db_, revoke ? "DELETE FROM case_shares WHERE case_id = ? AND user = ?"
                                     : "INSERT OR IGNORE INTO case_shares(case_id, user) "
                                       "VALUES(?, ?)"));
    change.Bind(1, id).Bind(2, user);
    return change.Run("share the case");
  }

  Status Delete(std::string_view id) override {
    std::lock_guard lock(mutex_);
    ASSIGN_OR_RETURN(SqliteStatement remove,
                     SqliteStatement::Prepare(db_, "DELETE FROM cases WHERE id = ?"));
    remove.Bind(1, id);
    // Its shares and events go with it (ON DELETE CASCADE).
    return RunOnCase(remove, id, "delete the case");
  }

 private:
  // Commits when `result` is OK, else rolls back and returns its error.
  template <typename T>
  Result<T> Finish(Result<T> result, std::string_view what) {
    if (result.ok()) {
      Status committed = db_.Exec("COMMIT", what);
      if (committed.ok()) return result;
      result = committed;
    }
    db_.Exec("ROLLBACK", "roll back").IgnoreError();
    return result;
  }

  Status RunOnCase(SqliteStatement& statement, std::string_view id, std::string_view what) {
    RETURN_IF_ERROR(statement.Run(what));
    if (sqlite3_changes(db_.get()) == 0) return CaseNotFound(id);
    return absl::OkStatus();
  }

  Status CheckExistsLocked(std::string_view id) {
    ASSIGN_OR_RETURN(SqliteStatement query,
                     SqliteStatement::Prepare(db_, "SELECT 1 FROM cases WHERE id = ?"));
    query.Bind(1, id);
    ASSIGN_OR_RETURN(const bool row, query.Step("find the case"));
    return row ? absl::OkStatus() : CaseNotFound(id);
  }

  Result<CaseRecord> GetLocked(std::string_view id) {
    ASSIGN_OR_RETURN(SqliteStatement query,
                     SqliteStatement::Prepare(
                         db_, StrCat("SELECT ", kCaseColumns, " FROM cases WHERE id = ?")));
    query.Bind(1, id);
    ASSIGN_OR_RETURN(const bool row, query.Step("read the case"));
    if (!row) return CaseNotFound(id);
    CaseRecord record = ReadCase(query);
    ASSIGN_OR_RETURN(record.shared_with, SharesLocked(record.id));
    return record;
  }

  Result<std::vector<std::string>> SharesLocked(const std::string& id) {
    ASSIGN_OR_RETURN(SqliteStatement query,
                     SqliteStatement::Prepare(
                         db_, "SELECT user FROM case_shares WHERE case_id = ? ORDER BY user"));
    query.Bind(1, id);
    std::vector<std::string> users;
    for (;;) {
      ASSIGN_OR_RETURN(const bool row, query.Step("read the case's shares"));
      if (!row) return users;
      users.push_back(query.Text(0));
    }
  }

  static CaseRecord ReadCase(const SqliteStatement& q) {
    CaseRecord r;
    r.id = q.Text(0);
    r.owner = q.Text(1);
    r.title = q.Text(2);
    r.notes = q.Text(3);
    r.source = q.Text(4);
    r.mesh_params = q.Text(5);
    r.camera = q.Text(6);
    r.created_ms = q.Int(7);
    r.modified_ms = q.Int(8);
    r.max_displacement_mm = q.Real(9);
    r.events = q.Int(10);
    r.undone = q.Int(11);
    return r;
  }

  static CaseEvent ReadEvent(const SqliteStatement& q) {
    CaseEvent e;
    e.seq = q.Int(0);
    e.op.kind = static_cast<SceneOp::Kind>(q.Int(1));
    const glm::dvec3 v(q.Real(2), q.Real(3), q.Real(4));
    if (e.op.kind == SceneOp::Kind::kGrab) {
      e.op.grab.point_mm = v;
      e.op.grab.rule = static_cast<GrabRule>(q.Int(5));
      e.op.grab.radius_mm = q.Real(6);
    } else {
      e.op.vector = v;
      e.op.radius_mm = q.Real(6);
    }
    e.op.keep = q.Int(7) != 0;
    e.time_ms = q.Int(8);
    return e;
  }

  Result<int64_t> AppendLocked(std::string_view id, const SceneOp& op, double max_disp) {
    RETURN_IF_ERROR(CheckExistsLocked(id));
    ASSIGN_OR_RETURN(SqliteStatement drop,
                     SqliteStatement::Prepare(db_, "DELETE FROM events WHERE case_id = ? AND "
                                                   "undone = 1"));
    drop.Bind(1, id);
    RETURN_IF_ERROR(drop.Run("drop undone events"));
    ASSIGN_OR_RETURN(SqliteStatement insert,
                     SqliteStatement::Prepare(
                         db_, "INSERT INTO events(case_id, seq, kind, x, y, z, rule, radius_mm, "
                              "keep, time_ms) SELECT ?1, coalesce(max(seq), 0) + 1, ?2, ?3, ?4, "
                              "?5, ?6, ?7, ?8, ?9 FROM events WHERE case_id = ?1 "
                              "RETURNING seq"));
    const bool grab = op.kind == SceneOp::Kind::kGrab;
    const glm::dvec3 v = grab ? op.grab.point_mm : op.vector;
    const int64_t now = NowMs();
    insert.Bind(1, id).Bind(2, static_cast<int64_t>(op.kind)).Bind(3, v.x).Bind(4, v.y);
    insert.Bind(5, v.z).Bind(6, static_cast<int64_t>(grab ? op.grab.rule : GrabRule::kOrgan));
    insert.Bind(7, grab ? op.grab.radius_mm : op.radius_mm)
        .Bind(8, static_cast<int64_t>(op.keep ? 1 : 0))
        .Bind(9, now);
    ASSIGN_OR_RETURN(const bool row, insert.Step("store an event"));
    if (!row) return absl::InternalError("case store: the event's seq was not returned");
    const int64_t seq = insert.Int(0);
    RETURN_IF_ERROR(insert.Run("store an event"));
    ASSIGN_OR_RETURN(SqliteStatement touch,
                     SqliteStatement::Prepare(db_, "UPDATE cases SET modified_ms = ?, "
                                                   "max_displacement_mm = ? WHERE id = ?"));
    touch.Bind(1, now).Bind(2, max_disp).Bind(3, id);
    RETURN_IF_ERROR(touch.Run("store an event"));
    return seq;
  }

  // The seq of the last action start in effect (undo) or the first undone
  // event (redo); 0 when none.
  Result<int64_t> FindSeq(std::string_view id, const char* sql) {
    ASSIGN_OR_RETURN(SqliteStatement query, SqliteStatement::Prepare(db_, sql));
    query.Bind(1, id);
    ASSIGN_OR_RETURN(const bool row, query.Step("find the action"));
    return row ? query.Int(0) : 0;
  }

  Result<bool> UndoLocked(std::string_view id) {
    RETURN_IF_ERROR(CheckExistsLocked(id));
    // Action starts: SceneOp::Kind kGrab 0, kPin 4, kReset 5 (StartsAction).
    ASSIGN_OR_RETURN(const int64_t from,
                     FindSeq(id, "SELECT coalesce(max(seq), 0) FROM events WHERE case_id = ? AND "
                                 "undone = 0 AND kind IN (0, 4, 5)"));
    if (from == 0) return false;
    ASSIGN_OR_RETURN(SqliteStatement mark,
                     SqliteStatement::Prepare(db_, "UPDATE events SET undone = 1 WHERE case_id "
                                                   "= ? AND seq >= ?"));
    mark.Bind(1, id).Bind(2, from);
    RETURN_IF_ERROR(mark.Run("undo"));
    return true;
  }

  Result<bool> RedoLocked(std::string_view id) {
    RETURN_IF_ERROR(CheckExistsLocked(id));
    ASSIGN_OR_RETURN(const int64_t from,
                     FindSeq(id, "SELECT coalesce(min(seq), 0) FROM events WHERE case_id = ? AND "
                                 "undone = 1"));
    if (from == 0) return false;
    // Up to the next action start after it (exclusive), or the end.
    ASSIGN_OR_RETURN(SqliteStatement next,
                     SqliteStatement::Prepare(
                         db_, "SELECT coalesce(min(seq), 9223372036854775807) FROM events WHERE "
                              "case_id = ? AND seq > ? AND kind IN (0, 4, 5)"));
    next.Bind(1, id).Bind(2, from);
    ASSIGN_OR_RETURN(const bool row, next.Step("redo"));
    const int64_t until = row ? next.Int(0) : INT64_MAX;
    ASSIGN_OR_RETURN(SqliteStatement mark,
                     SqliteStatement::Prepare(db_, "UPDATE events SET undone = 0 WHERE case_id "
                                                   "= ? AND seq >= ? AND seq < ?"));
    mark.Bind(1, id).Bind(2, from).Bind(3, until);
    RETURN_IF_ERROR(mark.Run("redo"));
    return true;
  }

  std::mutex mutex_;
  SqliteDb db_;
};

static_assert(static_cast<int>(SceneOp::Kind::kGrab) == 0 &&
              static_cast<int>(SceneOp::Kind::kPin) == 4 &&
              static_cast<int>(SceneOp::Kind::kReset) == 5,
              "the undo queries name the action starts by number");

Status Configure(const SqliteDb& db, const SqliteCaseStoreOptions& options) {
  sqlite3_busy_timeout(db.get(), options.busy_timeout_ms);
  ASSIGN_OR_RETURN(SqliteStatement wal, SqliteStatement::Prepare(db, "PRAGMA journal_mode=WAL"));
  ASSIGN_OR_RETURN(const bool row, wal.Step("turn on write-ahead logging"));
  if (!row || wal.Text(0) != "wal") {
    return absl::FailedPreconditionError(
        "case store: the state directory's file system does not support SQLite's write-ahead "
        "log (WAL); use a local disk");
  }
  RETURN_IF_ERROR(db.Exec("PRAGMA synchronous=NORMAL; PRAGMA foreign_keys=ON;",
                          "configure the database"));
  ASSIGN_OR_RETURN(SqliteStatement check, SqliteStatement::Prepare(db, "PRAGMA quick_check"));
  ASSIGN_OR_RETURN(const bool checked, check.Step("check the database"));
  if (!checked || check.Text(0) != "ok") {
    return absl::DataLossError(StrCat("case store: the database file is damaged (",
                                      checked ? check.Text(0) : "no answer",
                                      "); restore it from a backup"));
  }
  return absl::OkStatus();
}

}  // namespace

Result<std::unique_ptr<CaseStore>> OpenSqliteCaseStore(const std::filesystem::path& file,
                                                       const SqliteCaseStoreOptions& options) {
  sqlite3* raw = nullptr;
  const int rc = sqlite3_open_v2(file.c_str(), &raw, SQLITE_OPEN_READWRITE | SQLITE_OPEN_CREATE,
                                 nullptr);
  SqliteDb db(raw);
  if (rc != SQLITE_OK) {
    return SqliteError(rc, StrCat("open ", file.string()),
                       raw != nullptr ? sqlite3_errmsg(raw) : sqlite3_errstr(rc));
  }
  sqlite3_extended_result_codes(db.get(), 1);
  RETURN_IF_ERROR(Configure(db, options));
  RETURN_IF_ERROR(MigrateCaseSchema(db));
  return std::unique_ptr<CaseStore>(new SqliteCaseStore(std::move(db)));
}

}  // namespace vpm::cases
