#include "server/cases/sql_case_store.h"

#include <chrono>
#include <mutex>

#include "server/cases/case_schema.h"

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

SqlValue Text(std::string_view text) { return std::string(text); }

constexpr std::string_view kCaseColumns =
    "id, owner, title, notes, source, mesh_params, camera, created_ms, modified_ms, "
    "max_displacement_mm, render_settings, "
    "(SELECT count(*) FROM events e WHERE e.case_id = cases.id AND e.undone = 0), "
    "(SELECT count(*) FROM events e WHERE e.case_id = cases.id AND e.undone = 1)";

// Action starts (StartsAction): SceneOp::Kind kGrab 0, kPin 4, kReset 5.
static_assert(static_cast<int>(SceneOp::Kind::kGrab) == 0 &&
                  static_cast<int>(SceneOp::Kind::kPin) == 4 &&
                  static_cast<int>(SceneOp::Kind::kReset) == 5,
              "the undo statements name the action starts by number");
constexpr std::string_view kActionStarts = "(0, 4, 5)";

CaseRecord ReadCase(const SqlRow& r) {
  CaseRecord c;
  c.id = SqlText(r[0]);
  c.owner = SqlText(r[1]);
  c.title = SqlText(r[2]);
  c.notes = SqlText(r[3]);
  c.source = SqlText(r[4]);
  c.mesh_params = SqlText(r[5]);
  c.camera = SqlText(r[6]);
  c.created_ms = SqlInt(r[7]);
  c.modified_ms = SqlInt(r[8]);
  c.max_displacement_mm = SqlReal(r[9]);
  c.render_settings = SqlText(r[10]);
  c.events = SqlInt(r[11]);
  c.undone = SqlInt(r[12]);
  return c;
}

CaseEvent ReadEvent(const SqlRow& r) {
  CaseEvent e;
  e.seq = SqlInt(r[0]);
  e.op.kind = static_cast<SceneOp::Kind>(SqlInt(r[1]));
  const glm::dvec3 v(SqlReal(r[2]), SqlReal(r[3]), SqlReal(r[4]));
  if (e.op.kind == SceneOp::Kind::kGrab) {
    e.op.grab.point_mm = v;
    e.op.grab.rule = static_cast<GrabRule>(SqlInt(r[5]));
    e.op.grab.radius_mm = SqlReal(r[6]);
  } else {
    e.op.vector = v;
    e.op.radius_mm = SqlReal(r[6]);
  }
  e.op.keep = SqlInt(r[7]) != 0;
  e.time_ms = SqlInt(r[8]);
  e.settled = SqlInt(r[9]) != 0;
  return e;
}

class SqlCaseStore final : public CaseStore {
 public:
  explicit SqlCaseStore(std::unique_ptr<SqlConnection> db) : db_(std::move(db)) {}

  Status Create(const CaseRecord& r) override {
    if (r.id.empty() || r.owner.empty() || r.source.empty()) {
      return absl::InvalidArgumentError("case store: a case needs an id, an owner and a source");
    }
    std::lock_guard lock(mutex_);
    const int64_t now = NowMs();
    return db_
        ->Query("INSERT INTO cases(id, owner, title, notes, source, mesh_params, camera, "
                "render_settings, created_ms, modified_ms) "
                "VALUES($1, $2, $3, $4, $5, $6, $7, $8, $9, $10)",
                {Text(r.id), Text(r.owner), Text(r.title), Text(r.notes), Text(r.source),
                 SqlBlob{r.mesh_params}, SqlBlob{r.camera}, SqlBlob{r.render_settings}, now,
                 now},
                "create a case")
        .status();
  }

  Result<CaseRecord> Get(std::string_view id) override {
    std::lock_guard lock(mutex_);
    ASSIGN_OR_RETURN(std::vector<SqlRow> rows,
                     db_->Query(StrCat("SELECT ", kCaseColumns, " FROM cases WHERE id = $1"),
                                {Text(id)}, "read the case"));
    if (rows.empty()) return CaseNotFound(id);
    CaseRecord record = ReadCase(rows[0]);
    ASSIGN_OR_RETURN(record.shared_with, SharesLocked(record.id));
    return record;
  }

  Result<std::vector<CaseRecord>> List(std::string_view user) override {
    std::lock_guard lock(mutex_);
    ASSIGN_OR_RETURN(std::vector<SqlRow> rows,
                     db_->Query(StrCat("SELECT ", kCaseColumns,
                                       " FROM cases WHERE owner = $1 OR id IN (SELECT case_id "
                                       "FROM case_shares WHERE user_name = $1) ORDER BY "
                                       "modified_ms DESC, id"),
                                {Text(user)}, "list cases"));
    std::vector<CaseRecord> out;
    for (const SqlRow& row : rows) {
      out.push_back(ReadCase(row));
      ASSIGN_OR_RETURN(out.back().shared_with, SharesLocked(out.back().id));
    }
    return out;
  }

  Result<int64_t> Append(std::string_view id, const SceneOp& op,
                         double max_displacement_mm) override {
    std::lock_guard lock(mutex_);
    RETURN_IF_ERROR(db_->Begin("store an event"));
    return Finish(AppendLocked(id, op, max_displacement_mm), "store an event");
  }

  Result<std::vector<CaseEvent>> Events(std::string_view id) override {
    std::lock_guard lock(mutex_);
    RETURN_IF_ERROR(CheckExistsLocked(id, false));
    ASSIGN_OR_RETURN(std::vector<SqlRow> rows,
                     db_->Query("SELECT seq, kind, x, y, z, rule, radius_mm, keep, time_ms, "
                                "settled FROM events WHERE case_id = $1 AND undone = 0 ORDER BY "
                                "seq",
                                {Text(id)}, "read a case's events"));
    std::vector<CaseEvent> out;
    out.reserve(rows.size());
    for (const SqlRow& row : rows) out.push_back(ReadEvent(row));
    return out;
  }

  Result<bool> Undo(std::string_view id) override {
    std::lock_guard lock(mutex_);
    RETURN_IF_ERROR(db_->Begin("undo"));
    return Finish(UndoLocked(id), "undo");
  }

  Result<bool> Redo(std::string_view id) override {
    std::lock_guard lock(mutex_);
    RETURN_IF_ERROR(db_->Begin("redo"));
    return Finish(RedoLocked(id), "redo");
  }

  Status MarkSettled(std::string_view id) override {
    std::lock_guard lock(mutex_);
    RETURN_IF_ERROR(CheckExistsLocked(id, false));
    return db_
        ->Query("UPDATE events SET settled = 1 WHERE case_id = $1 AND seq = (SELECT max(seq) "
                "FROM events WHERE case_id = $1 AND undone = 0)",
                {Text(id)}, "mark the case settled")
        .status();
  }

  Status SetCamera(std::string_view id, const std::string& camera) override {
    std::lock_guard lock(mutex_);
    return UpdateOne("UPDATE cases SET camera = $1, modified_ms = $2 WHERE id = $3 RETURNING id",
                     {SqlBlob{camera}, NowMs(), Text(id)}, id, "store the camera");
  }

  Status SetRenderSettings(std::string_view id, const std::string& render_settings) override {
    std::lock_guard lock(mutex_);
    return UpdateOne(
        "UPDATE cases SET render_settings = $1, modified_ms = $2 WHERE id = $3 RETURNING id",
        {SqlBlob{render_settings}, NowMs(), Text(id)}, id, "store the render settings");
  }

  Status SetDisplacement(std::string_view id, double max_displacement_mm) override {
    std::lock_guard lock(mutex_);
    return UpdateOne("UPDATE cases SET max_displacement_mm = $1 WHERE id = $2 RETURNING id",
                     {max_displacement_mm, Text(id)}, id, "store the displacement");
  }

  Status SetMeshParams(std::string_view id, const std::string& mesh_params) override {
    std::lock_guard lock(mutex_);
    return UpdateOne("UPDATE cases SET mesh_params = $1 WHERE id = $2 RETURNING id",
                     {SqlBlob{mesh_params}, Text(id)}, id, "store the mesh parameters");
  }

  Status Update(std::string_view id, const std::optional<std::string>& title,
                const std::optional<std::string>& notes) override {
    std::lock_guard lock(mutex_);
    return UpdateOne(
        "UPDATE cases SET title = coalesce($1, title), notes = coalesce($2, notes), "
        "modified_ms = $3 WHERE id = $4 RETURNING id",
        {title ? SqlValue(*title) : SqlValue(), notes ? SqlValue(*notes) : SqlValue(), NowMs(),
         Text(id)},
        id, "rename the case");
  }

  Status Share(std::string_view id, const std::string& user, bool revoke) override {
    std::lock_guard lock(mutex_);
    RETURN_IF_ERROR(CheckExistsLocked(id, false));
    return db_
        ->Query(revoke ? "DELETE FROM case_shares WHERE case_id = $1 AND user_name = $2"
                       : "INSERT INTO case_shares(case_id, user_name) VALUES($1, $2) "
                         "ON CONFLICT DO NOTHING",
                {Text(id), Text(user)}, "share the case")
        .status();
  }

  Status Delete(std::string_view id) override {
    std::lock_guard lock(mutex_);
    // Its shares and events go with it (ON DELETE CASCADE).
    return UpdateOne("DELETE FROM cases WHERE id = $1 RETURNING id", {Text(id)}, id,
                     "delete the case");
  }

  Result<int64_t> CountWithSource(std::string_view source) override {
    std::lock_guard lock(mutex_);
    return Scalar("SELECT count(*) FROM cases WHERE source = $1", {Text(source)},
                  "count the cases of a source");
  }

 private:
  // Commits when `result` is OK, else rolls back and returns its error.
  template <typename T>
  Result<T> Finish(Result<T> result, std::string_view what) {
    if (result.ok()) {
      Status committed = db_->Commit(what);
      if (committed.ok()) return result;
      result = committed;
    }
    db_->Rollback();
    return result;
  }

  // A statement ending in RETURNING id: NotFound when it touched no row.
  Status UpdateOne(std::string_view sql, const std::vector<SqlValue>& params,
                   std::string_view id, std::string_view what) {
    ASSIGN_OR_RETURN(std::vector<SqlRow> rows, db_->Query(sql, params, what));
    return rows.empty() ? CaseNotFound(id) : absl::OkStatus();
  }

  // lock: inside a write transaction, hold the case's row until commit (a
  // second replica appending to the same case waits).
  Status CheckExistsLocked(std::string_view id, bool lock) {
    ASSIGN_OR_RETURN(std::vector<SqlRow> rows,
                     db_->Query(StrCat("SELECT 1 FROM cases WHERE id = $1",
                                       lock ? db_->LockRowSuffix() : ""),
                                {Text(id)}, "find the case"));
    return rows.empty() ? CaseNotFound(id) : absl::OkStatus();
  }

  Result<std::vector<std::string>> SharesLocked(const std::string& id) {
    ASSIGN_OR_RETURN(std::vector<SqlRow> rows,
                     db_->Query("SELECT user_name FROM case_shares WHERE case_id = $1 ORDER BY "
                                "user_name",
                                {Text(id)}, "read the case's shares"));
    std::vector<std::string> users;
    for (const SqlRow& row : rows) users.push_back(SqlText(row[0]));
    return users;
  }

  Result<int64_t> AppendLocked(std::string_view id, const SceneOp& op, double max_disp) {
    RETURN_IF_ERROR(CheckExistsLocked(id, true));
    RETURN_IF_ERROR(db_->Query("DELETE FROM events WHERE case_id = $1 AND undone = 1",
                               {Text(id)}, "drop undone events")
                        .status());
    const bool grab = op.kind == SceneOp::Kind::kGrab;
    const glm::dvec3 v = grab ? op.grab.point_mm : op.vector;
    const int64_t now = NowMs();
    ASSIGN_OR_RETURN(
        std::vector<SqlRow> rows,
        db_->Query("INSERT INTO events(case_id, seq, kind, x, y, z, rule, radius_mm, keep, "
                   "undone, time_ms) SELECT $1, coalesce(max(seq), 0) + 1, $2, $3, $4, $5, $6, "
                   "$7, $8, 0, $9 FROM events WHERE case_id = $1 RETURNING seq",
                   {Text(id), static_cast<int64_t>(op.kind), v.x, v.y, v.z,
                    static_cast<int64_t>(grab ? op.grab.rule : GrabRule::kOrgan),
                    grab ? op.grab.radius_mm : op.radius_mm, int64_t{op.keep ? 1 : 0}, now},
                   "store an event"));
    if (rows.empty()) return absl::InternalError("case store: the event's seq was not returned");
    const int64_t seq = SqlInt(rows[0][0]);
    RETURN_IF_ERROR(db_->Query("UPDATE cases SET modified_ms = $1, max_displacement_mm = $2 "
                               "WHERE id = $3",
                               {now, max_disp, Text(id)}, "store an event")
                        .status());
    return seq;
  }

  // The first value of the only row of `sql` (0 when NULL).
  Result<int64_t> Scalar(std::string_view sql, const std::vector<SqlValue>& params,
                         std::string_view what) {
    ASSIGN_OR_RETURN(std::vector<SqlRow> rows, db_->Query(sql, params, what));
    return rows.empty() ? 0 : SqlInt(rows[0][0]);
  }

  Result<bool> UndoLocked(std::string_view id) {
    RETURN_IF_ERROR(CheckExistsLocked(id, true));
    ASSIGN_OR_RETURN(const int64_t from,
                     Scalar(StrCat("SELECT coalesce(max(seq), 0) FROM events WHERE case_id = $1 "
                                   "AND undone = 0 AND kind IN ",
                                   kActionStarts),
                            {Text(id)}, "undo"));
    if (from == 0) return false;
    RETURN_IF_ERROR(db_->Query("UPDATE events SET undone = 1 WHERE case_id = $1 AND seq >= $2",
                               {Text(id), from}, "undo")
                        .status());
    return true;
  }

  Result<bool> RedoLocked(std::string_view id) {
    RETURN_IF_ERROR(CheckExistsLocked(id, true));
    ASSIGN_OR_RETURN(const int64_t from,
                     Scalar("SELECT coalesce(min(seq), 0) FROM events WHERE case_id = $1 AND "
                            "undone = 1",
                            {Text(id)}, "redo"));
    if (from == 0) return false;
    // Up to the next action start after it (exclusive), or the end.
    ASSIGN_OR_RETURN(const int64_t next,
                     Scalar(StrCat("SELECT coalesce(min(seq), 0) FROM events WHERE case_id = $1 "
                                   "AND seq > $2 AND kind IN ",
                                   kActionStarts),
                            {Text(id), from}, "redo"));
    const int64_t until = next == 0 ? INT64_MAX : next;
    RETURN_IF_ERROR(db_->Query("UPDATE events SET undone = 0 WHERE case_id = $1 AND seq >= $2 "
                               "AND seq < $3",
                               {Text(id), from, until}, "redo")
                        .status());
    return true;
  }

  std::mutex mutex_;
  std::unique_ptr<SqlConnection> db_;
};

}  // namespace

std::vector<SceneOp> ReplayLog(const std::vector<CaseEvent>& events) {
  std::vector<SceneOp> log;
  log.reserve(events.size());
  for (const CaseEvent& event : events) {
    log.push_back(event.op);
    if (event.settled) log.push_back({.kind = SceneOp::Kind::kSettle});
  }
  return log;
}

int64_t SqlInt(const SqlValue& value) {
  if (const auto* i = std::get_if<int64_t>(&value)) return *i;
  if (const auto* d = std::get_if<double>(&value)) return static_cast<int64_t>(*d);
  if (const auto* s = std::get_if<std::string>(&value)) return std::strtoll(s->c_str(), nullptr, 10);
  return 0;
}

double SqlReal(const SqlValue& value) {
  if (const auto* d = std::get_if<double>(&value)) return *d;
  if (const auto* i = std::get_if<int64_t>(&value)) return static_cast<double>(*i);
  if (const auto* s = std::get_if<std::string>(&value)) return std::strtod(s->c_str(), nullptr);
  return 0.0;
}

std::string SqlText(const SqlValue& value) {
  if (const auto* s = std::get_if<std::string>(&value)) return *s;
  if (const auto* b = std::get_if<SqlBlob>(&value)) return b->bytes;
  if (const auto* i = std::get_if<int64_t>(&value)) return std::to_string(*i);
  return "";
}

Result<std::unique_ptr<CaseStore>> MakeSqlCaseStore(std::unique_ptr<SqlConnection> connection) {
  RETURN_IF_ERROR(MigrateCaseSchema(*connection));
  return std::unique_ptr<CaseStore>(new SqlCaseStore(std::move(connection)));
}

}  // namespace vpm::cases
