// The one interface to stored cases (docs/CASES.md). Every call is a
// transaction: it happens whole or not at all. Errors: NotFound for an
// unknown case id; ResourceExhausted when the disk (or the database's
// quota) is full; Unavailable while the database is locked; DataLoss for a
// damaged database; InvalidArgument for a malformed record. Thread-safe.
#pragma once

#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "server/cases/case_record.h"
#include "server/common/status.h"

namespace vpm::cases {

class CaseStore {
 public:
  virtual ~CaseStore() = default;

  // A new case (record.id unique; events and times are the store's).
  virtual Status Create(const CaseRecord& record) = 0;
  virtual Result<CaseRecord> Get(std::string_view id) = 0;
  // The cases `user` owns or that are shared with them, newest change first.
  virtual Result<std::vector<CaseRecord>> List(std::string_view user) = 0;
  // Appends `op` after the last event in effect, first dropping the undone
  // ones (a new branch), and stores the displacement it left. Returns its seq.
  virtual Result<int64_t> Append(std::string_view id, const SceneOp& op,
                                 double max_displacement_mm) = 0;
  // The events in effect, in order.
  virtual Result<std::vector<CaseEvent>> Events(std::string_view id) = 0;
  // Takes back the last action in effect (a grab with its drags and
  // release, a pin, a reset: StartsAction) / brings back the first undone
  // one. False when there is none.
  virtual Result<bool> Undo(std::string_view id) = 0;
  virtual Result<bool> Redo(std::string_view id) = 0;
  // A still frame settled the state the last event in effect left: the
  // event is marked (CaseEvent::settled). Nothing happens without events.
  virtual Status MarkSettled(std::string_view id) = 0;
  virtual Status SetCamera(std::string_view id, const std::string& camera) = 0;
  // The render settings it reopens with (CaseRecord::render_settings).
  virtual Status SetRenderSettings(std::string_view id, const std::string& render_settings) = 0;
  virtual Status SetDisplacement(std::string_view id, double max_displacement_mm) = 0;
  // The mesh the case reopens on (serialized v3.MeshParams): a refinement
  // swapped into its session.
  virtual Status SetMeshParams(std::string_view id, const std::string& mesh_params) = 0;
  virtual Status Update(std::string_view id, const std::optional<std::string>& title,
                        const std::optional<std::string>& notes) = 0;
  virtual Status Share(std::string_view id, const std::string& user, bool revoke) = 0;
  // The case and everything stored of it.
  virtual Status Delete(std::string_view id) = 0;
  // How many cases keep `source` (a kept upload is removed with its last).
  virtual Result<int64_t> CountWithSource(std::string_view source) = 0;
};

}  // namespace vpm::cases
