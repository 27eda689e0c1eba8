// Where `vpm play` goes on in a reopened case (client/common/script_resume.h):
// after the script event the case's last manipulation matches, whatever
// drags the server replaced in its queue.
#include "client/common/script_resume.h"

#include <vector>

#include <gtest/gtest.h>

#include "proto/vec3_convert.h"

namespace vpm::cli {
namespace {

v3::Vec3 V(double x, double y, double z) { return ToProto(glm::dvec3(x, y, z)); }

// camera, grab, drags to (0, 0, k) for k = 1..5, camera, kept release.
Script FiveDrags() {
  Script script;
  auto add = [&](auto fill) {
    ScriptEvent e;
    fill(e.event);
    script.events.push_back(e);
  };
  add([](v3::ClientEvent& e) { e.mutable_camera()->set_azimuth_deg(10); });
  add([](v3::ClientEvent& e) { *e.mutable_grab()->mutable_point_mm() = V(1, 2, 3); });
  for (int k = 1; k <= 5; ++k) {
    add([k](v3::ClientEvent& e) { *e.mutable_drag()->mutable_offset_mm() = V(0, 0, k); });
  }
  add([](v3::ClientEvent& e) { e.mutable_camera()->set_azimuth_deg(20); });
  add([](v3::ClientEvent& e) { e.mutable_release()->set_keep(true); });
  return script;
}

v3::CaseArchiveEvent Event(v3::CaseEventKind kind, double z = 0, bool keep = false) {
  v3::CaseArchiveEvent e;
  e.set_kind(kind);
  *e.mutable_vector() = V(0, 0, z);
  e.set_keep(keep);
  return e;
}

Result<int64_t> Resume(const Script& script, const std::vector<v3::CaseArchiveEvent>& events) {
  return IndexAfterCaseEvents(script, events);
}

TEST(ScriptResume, EveryDragKeptGoesOnAfterTheLastOneLikeACount) {
  const Script script = FiveDrags();
  std::vector<v3::CaseArchiveEvent> events{Event(v3::CASE_EVENT_GRAB)};
  for (int k = 1; k <= 3; ++k) events.push_back(Event(v3::CASE_EVENT_DRAG, k));
  ASSERT_TRUE(Resume(script, events).ok());
  EXPECT_EQ(*Resume(script, events), 5);  // the drag to 4 next
  EXPECT_EQ(IndexAfterManipulations(script, 4), 5);
  EXPECT_EQ(*Resume(script, {}), 0);
}

TEST(ScriptResume, DragsReplacedInTheQueueAreNotSentAgain) {
  const Script script = FiveDrags();
  // The drags to 1 and 3 were replaced by the next ones.
  const std::vector<v3::CaseArchiveEvent> events{
      Event(v3::CASE_EVENT_GRAB), Event(v3::CASE_EVENT_REMESH), Event(v3::CASE_EVENT_DRAG, 2),
      Event(v3::CASE_EVENT_DRAG, 4)};
  ASSERT_TRUE(Resume(script, events).ok()) << Resume(script, events).status();
  EXPECT_EQ(*Resume(script, events), 6);  // the drag to 5 next, not the one to 3
  EXPECT_EQ(IndexAfterManipulations(script, 4), 5);  // a count would send 3 and 4 again
  const std::vector<v3::CaseArchiveEvent> all{Event(v3::CASE_EVENT_GRAB),
                                              Event(v3::CASE_EVENT_DRAG, 5),
                                              Event(v3::CASE_EVENT_RELEASE, 0, true)};
  EXPECT_EQ(*Resume(script, all), 9);  // nothing left
}

TEST(ScriptResume, EventsNotTheScriptsAreNotFound) {
  const Script script = FiveDrags();
  // A drag off the script's path, a drag out of order, a release whose
  // keep differs, a release with the last drag missing (a drag is replaced
  // only by the drag right after it), a pin the script does not have.
  const std::vector<std::vector<v3::CaseArchiveEvent>> foreign{
      {Event(v3::CASE_EVENT_GRAB), Event(v3::CASE_EVENT_DRAG, 2.5)},
      {Event(v3::CASE_EVENT_GRAB), Event(v3::CASE_EVENT_DRAG, 3), Event(v3::CASE_EVENT_DRAG, 2)},
      {Event(v3::CASE_EVENT_GRAB), Event(v3::CASE_EVENT_DRAG, 5), Event(v3::CASE_EVENT_RELEASE)},
      {Event(v3::CASE_EVENT_GRAB), Event(v3::CASE_EVENT_RELEASE, 0, true)},
      {Event(v3::CASE_EVENT_PIN)},
  };
  for (size_t i = 0; i < foreign.size(); ++i) {
    const Result<int64_t> index = Resume(script, foreign[i]);
    EXPECT_TRUE(absl::IsNotFound(index.status())) << "case " << i << ": " << index.status();
  }
}

}  // namespace
}  // namespace vpm::cli
