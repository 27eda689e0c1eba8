#include "client/common/script_resume.h"

#include <cmath>

#include "proto/client_event_kind.h"

namespace vpm::cli {
namespace {

// Offsets and forces come back from the case in world LPS, possibly through
// a change of frame: equal within 1e-4 (mm or N; script steps are far
// coarser).
bool Near(const v3::Vec3& a, const v3::Vec3& b) {
  constexpr double kTolerance = 1e-4;
  return std::abs(a.x() - b.x()) <= kTolerance && std::abs(a.y() - b.y()) <= kTolerance &&
         std::abs(a.z() - b.z()) <= kTolerance;
}

bool Matches(const v3::ClientEvent& s, const v3::CaseArchiveEvent& e) {
  switch (e.kind()) {
    case v3::CASE_EVENT_GRAB: return s.has_grab();
    case v3::CASE_EVENT_DRAG: return s.has_drag() && Near(s.drag().offset_mm(), e.vector());
    case v3::CASE_EVENT_PULL: return s.has_pull() && Near(s.pull().force_n(), e.vector());
    case v3::CASE_EVENT_RELEASE: return s.has_release() && s.release().keep() == e.keep();
    case v3::CASE_EVENT_PIN: return s.has_pin();
    case v3::CASE_EVENT_RESET: return s.has_reset();
    default: return false;
  }
}

}  // namespace

Result<int64_t> IndexAfterCaseEvents(const Script& script,
                                     std::span<const v3::CaseArchiveEvent> events) {
  size_t next = 0;  // script index where the next event's match is looked for
  for (size_t k = 0; k < events.size(); ++k) {
    const v3::CaseArchiveEvent& e = events[k];
    if (e.kind() == v3::CASE_EVENT_REMESH) continue;  // the server's own
    bool matched = false;
    for (size_t i = next; i < script.events.size() && !matched; ++i) {
      const v3::ClientEvent& s = script.events[i].event;
      if (!IsManipulation(s)) continue;
      if (Matches(s, e)) {
        next = i + 1;
        matched = true;
      } else if (!s.has_drag() || i + 1 == script.events.size() ||
                 !script.events[i + 1].event.has_drag()) {
        break;  // only a drag followed by a drag is ever replaced in the queue
      }
    }
    if (!matched) {
      return absl::NotFoundError(StrCat("the case's event ", k + 1, " of ", events.size(),
                                        " is not the script's next manipulation"));
    }
  }
  return static_cast<int64_t>(next);
}

int64_t IndexAfterManipulations(const Script& script, int64_t manipulations) {
  int64_t seen = 0;
  for (size_t i = 0; i < script.events.size(); ++i) {
    if (seen == manipulations) return static_cast<int64_t>(i);
    if (IsManipulation(script.events[i].event)) ++seen;
  }
  return static_cast<int64_t>(script.events.size());
}

}  // namespace vpm::cli
