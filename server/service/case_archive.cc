#include "server/service/case_archive.h"

#include <cmath>

#include "server/service/mesh_store.h"
#include "server/service/proto_convert.h"

namespace vpm::service {
namespace {

v3::CaseEventKind KindToApi(SceneOp::Kind kind) {
  switch (kind) {
    case SceneOp::Kind::kGrab: return v3::CASE_EVENT_GRAB;
    case SceneOp::Kind::kDrag: return v3::CASE_EVENT_DRAG;
    case SceneOp::Kind::kPull: return v3::CASE_EVENT_PULL;
    case SceneOp::Kind::kRelease: return v3::CASE_EVENT_RELEASE;
    case SceneOp::Kind::kPin: return v3::CASE_EVENT_PIN;
    case SceneOp::Kind::kReset: return v3::CASE_EVENT_RESET;
    case SceneOp::Kind::kRemesh: return v3::CASE_EVENT_REMESH;
    case SceneOp::Kind::kSettle: break;  // never stored as an event
  }
  return v3::CASE_EVENT_KIND_UNSPECIFIED;
}

Result<SceneOp::Kind> KindFromApi(v3::CaseEventKind kind) {
  switch (kind) {
    case v3::CASE_EVENT_GRAB: return SceneOp::Kind::kGrab;
    case v3::CASE_EVENT_DRAG: return SceneOp::Kind::kDrag;
    case v3::CASE_EVENT_PULL: return SceneOp::Kind::kPull;
    case v3::CASE_EVENT_RELEASE: return SceneOp::Kind::kRelease;
    case v3::CASE_EVENT_PIN: return SceneOp::Kind::kPin;
    case v3::CASE_EVENT_RESET: return SceneOp::Kind::kReset;
    case v3::CASE_EVENT_REMESH: return SceneOp::Kind::kRemesh;
    default: return absl::InvalidArgumentError(StrCat("kind ", static_cast<int>(kind), " is unknown"));
  }
}

bool Finite(const glm::dvec3& v) {
  return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
}

// One archived event in physical voxel space (`at`: "events[i]").
Result<cases::CaseEvent> FromApi(const v3::CaseArchiveEvent& in, const VolumeGeometry& geometry,
                                 const std::string& at) {
  cases::CaseEvent e;
  Result<SceneOp::Kind> kind = KindFromApi(in.kind());
  if (!kind.ok()) return absl::InvalidArgumentError(StrCat(at, ".", kind.status().message()));
  e.op.kind = *kind;
  const glm::dvec3 point = PointFromApi(in.point_mm(), geometry);
  const glm::dvec3 vector = VectorFromApi(in.vector(), geometry);
  if (!Finite(point) || !Finite(vector) || !std::isfinite(in.radius_mm()) || in.radius_mm() < 0) {
    return absl::InvalidArgumentError(StrCat(at, ": a number is not finite (or a radius < 0)"));
  }
  const bool has_point = e.op.kind == SceneOp::Kind::kGrab || e.op.kind == SceneOp::Kind::kPin ||
                         e.op.kind == SceneOp::Kind::kRemesh;
  if (has_point) RETURN_IF_ERROR(CheckInsideVolume(geometry, point, StrCat(at, ".point_mm")));
  if (e.op.kind == SceneOp::Kind::kGrab) {
    e.op.grab = {.point_mm = point,
                 .rule = in.rule() == v3::GRAB_RULE_BALL ? GrabRule::kBall : GrabRule::kOrgan,
                 .radius_mm = in.radius_mm()};
  } else {
    e.op.vector = has_point ? point : vector;
    e.op.radius_mm = in.radius_mm();
  }
  e.op.keep = in.keep();
  e.settled = in.settled();
  e.time_ms = in.unix_ms();
  return e;
}

}  // namespace

v3::CaseArchive ToCaseArchive(const cases::CaseRecord& record,
                              const std::vector<cases::CaseEvent>& events,
                              const VolumeGeometry& geometry) {
  v3::CaseArchive out;
  out.set_format_version(kCaseArchiveVersion);
  out.set_title(record.title);
  out.set_notes(record.notes);
  out.set_source(record.source);
  out.mutable_mesh_params()->ParseFromString(record.mesh_params);
  if (!record.camera.empty()) out.mutable_camera()->ParseFromString(record.camera);
  if (!record.render_settings.empty()) out.mutable_view()->ParseFromString(record.render_settings);
  out.set_created_unix_ms(record.created_ms);
  for (const cases::CaseEvent& e : events) {
    v3::CaseArchiveEvent* a = out.add_events();
    a->set_kind(KindToApi(e.op.kind));
    if (e.op.kind == SceneOp::Kind::kGrab) {
      *a->mutable_point_mm() = PointToApi(e.op.grab.point_mm, geometry);
      a->set_rule(e.op.grab.rule == GrabRule::kBall ? v3::GRAB_RULE_BALL : v3::GRAB_RULE_ORGAN);
      a->set_radius_mm(e.op.grab.radius_mm);
    } else if (e.op.kind == SceneOp::Kind::kPin || e.op.kind == SceneOp::Kind::kRemesh) {
      *a->mutable_point_mm() = PointToApi(e.op.vector, geometry);
      a->set_radius_mm(e.op.radius_mm);
    } else if (e.op.kind == SceneOp::Kind::kDrag || e.op.kind == SceneOp::Kind::kPull) {
      const glm::dvec3 w = geometry.PhysicalVectorToWorld(e.op.vector);
      a->mutable_vector()->set_x(w.x);
      a->mutable_vector()->set_y(w.y);
      a->mutable_vector()->set_z(w.z);
    }
    a->set_keep(e.op.keep);
    a->set_settled(e.settled);
    a->set_unix_ms(e.time_ms);
  }
  return out;
}

Result<std::vector<cases::CaseEvent>> EventsFromArchive(const v3::CaseArchive& archive,
                                                        const VolumeGeometry& geometry) {
  if (archive.format_version() != kCaseArchiveVersion) {
    return absl::InvalidArgumentError(StrCat("archive.format_version: ", archive.format_version(),
                                             " is not ", kCaseArchiveVersion,
                                             " (written by another vpm?)"));
  }
  if (archive.events_size() > kMaxArchiveEvents) {
    return absl::InvalidArgumentError(StrCat("archive.events: ", archive.events_size(),
                                             " events, more than ", kMaxArchiveEvents));
  }
  std::vector<cases::CaseEvent> events;
  events.reserve(archive.events_size());
  for (int i = 0; i < archive.events_size(); ++i) {
    ASSIGN_OR_RETURN(cases::CaseEvent e,
                     FromApi(archive.events(i), geometry, StrCat("archive.events[", i, "]")));
    events.push_back(e);
  }
  return events;
}

}  // namespace vpm::service
