// Slices over the API: RenderSlice against the CPU reference slice of the
// same deformed volume, its refusals of bad input, and slices riding along
// with Interact frames (RenderSettings.slices).
//
// Tolerance, RenderSlice against the CPU reference (grey levels of a PNG,
// window W 400 L 40: 1 grey level = 1.6 HU): mean |difference| < 1.5 and
// 99% of pixels within 12 levels (about 19 HU). The server's slice reads
// the GPU backward map (built by its own kernel, sampled with the
// sampler's fixed-point weights) and the GPU slice kernel; the reference
// builds the map with BackwardMapCpu and samples it in double
// (server/warp/backward_map_cpu.h, server/raycast/slice_sampler.h), so
// pixels on the phantom's sharpest edges differ by a few levels.
#include <algorithm>
#include <cmath>
#include <cstdio>

#include "server/raycast/frame_encoder.h"
#include "server/raycast/slice_image.h"
#include "server/raycast/slice_sampler.h"
#include "server/warp/backward_map_cpu.h"
#include "tests/service/service_test_util.h"

namespace vpm::service::testing {
namespace {

// An axial slice at world z = at_mm (LPS), window 400 / 40.
v3::SliceSpec Axial(double at_mm) {
  v3::SliceSpec spec;
  spec.set_orientation(v3::SLICE_ORIENTATION_AXIAL);
  spec.set_at_mm(at_mm);
  spec.mutable_window()->set_width(400);
  spec.mutable_window()->set_level(40);
  return spec;
}

class RenderSliceTest : public PhantomSessionTest {
 protected:
  grpc::Status RenderSlice(const v3::SliceSpec& spec, v3::Frame* frame,
                           const std::string& session_id = "") {
    v3::RenderSliceRequest request;
    request.set_session_id(session_id.empty() ? session_.session_id() : session_id);
    *request.mutable_slice() = spec;
    request.set_encoding(v3::ENCODING_PNG);
    auto context = Context();
    return stub_->RenderSlice(context.get(), request, frame);
  }

  // Grabs the centre and drags it `drag_mm` along x over an Interact
  // stream; returns the deformed vertex positions the last frame carried.
  std::vector<glm::dvec3> GrabAndDrag(double drag_mm) {
    auto context = Context();
    auto stream = stub_->Interact(context.get());
    v3::InteractRequest grab;
    grab.set_session_id(session_.session_id());
    grab.mutable_event()->set_sequence(1);
    *grab.mutable_event()->mutable_grab()->mutable_point_mm() = Centre(volume_);
    EXPECT_TRUE(stream->Write(grab));
    v3::InteractRequest drag;
    drag.mutable_event()->set_sequence(2);
    *drag.mutable_event()->mutable_drag()->mutable_offset_mm() = V(drag_mm, 0, 0);
    drag.mutable_event()->set_want_vertices(true);
    EXPECT_TRUE(stream->Write(drag));
    std::vector<glm::dvec3> deformed;
    v3::Frame frame;
    while (stream->Read(&frame)) {
      if (frame.last_sequence() == 2 && frame.vertices_mm_size() > 0) {
        for (const v3::Vec3& p : frame.vertices_mm()) deformed.push_back(FromProto(p));
        break;
      }
    }
    stream->WritesDone();
    while (stream->Read(&frame)) {
    }
    EXPECT_TRUE(stream->Finish().ok());
    return deformed;
  }

};

DecodedImage DecodeFramePng(const std::string& bytes) {
  auto decoded = DecodePng({reinterpret_cast<const uint8_t*>(bytes.data()), bytes.size()});
  EXPECT_TRUE(decoded.ok()) << decoded.status();
  return decoded.ok() ? *std::move(decoded) : DecodedImage{};
}

// The backward map of a deformation on the CPU at the server's map
// resolution: the mesh's rest positions and `deformed` (both world LPS, as
// the API gives them) taken into the volume's physical voxel space.
Result<BackwardMapValues> CpuMap(const v3::GetMeshResponse& mesh, std::vector<glm::dvec3> deformed,
                                 const VolumeGeometry& g) {
  std::vector<glm::dvec3> rest;
  for (const v3::MeshVertex& v : mesh.vertices()) {
    rest.push_back(g.WorldToPhysical(FromProto(v.position_mm())));
  }
  for (glm::dvec3& p : deformed) p = g.WorldToPhysical(p);
  std::vector<std::array<int32_t, 4>> tets;
  for (const v3::Tet& t : mesh.tets()) tets.push_back({t.a(), t.b(), t.c(), t.d()});
  if (rest.size() != deformed.size()) return absl::InternalError("vertex counts differ");
  return BackwardMapCpu(g.extent_mm(), DefaultBackwardMapDims(g.dims), rest, deformed, tets);
}

// A slice of the API and the same plane for the CPU reference.
struct SliceCase {
  const char* name;
  v3::SliceSpec spec;
  SlicePlane plane;
};

// Axial through the centre, coronal 2 mm from it along +y, oblique (normal
// 1, 1, 2) through it; centre in world LPS mm.
std::vector<SliceCase> SliceCases(const glm::dvec3& centre) {
  std::vector<SliceCase> cases;
  cases.push_back(
      {"axial", Axial(centre.z), {.orientation = SliceOrientation::kAxial, .at_mm = centre.z}});
  v3::SliceSpec coronal = Axial(0);
  coronal.set_orientation(v3::SLICE_ORIENTATION_CORONAL);
  coronal.set_at_mm(centre.y + 2.0);
  cases.push_back(
      {"coronal", coronal, {.orientation = SliceOrientation::kCoronal, .at_mm = centre.y + 2.0}});
  v3::SliceSpec oblique = Axial(0);
  oblique.clear_at_mm();
  oblique.set_orientation(v3::SLICE_ORIENTATION_OBLIQUE);
  *oblique.mutable_point_lps_mm() = ToProto(centre);
  *oblique.mutable_normal() = ToProto(glm::dvec3(1, 1, 2));
  cases.push_back({"oblique",
                   oblique,
                   {.orientation = SliceOrientation::kOblique,
                    .point_mm = centre,
                    .normal = glm::dvec3(1, 1, 2)}});
  return cases;
}

// Grey levels (the red channel) of the frame against the reference, and of
// the reference against the volume at rest.
struct GreyDifference {
  double mean = 0.0;        // mean |frame - reference|
  int64_t far = 0;          // pixels over 12 levels apart
  double moved_mean = 0.0;  // mean |reference - at rest|
};

GreyDifference CompareGrey(const std::vector<uint8_t>& got, const std::vector<uint8_t>& reference,
                           const std::vector<uint8_t>& at_rest) {
  GreyDifference diff;
  const int64_t pixels = static_cast<int64_t>(reference.size() / 4);
  for (int64_t i = 0; i < pixels; ++i) {
    const int d = std::abs(int(got[4 * i]) - int(reference[4 * i]));
    diff.mean += d;
    diff.moved_mean += std::abs(int(reference[4 * i]) - int(at_rest[4 * i]));
    if (d > 12) ++diff.far;
  }
  diff.mean /= double(pixels);
  diff.moved_mean /= double(pixels);
  return diff;
}

TEST_F(RenderSliceTest, RenderSlice_MatchesTheCpuReferenceOfTheDeformedVolume) {
  std::vector<glm::dvec3> deformed = GrabAndDrag(6.0);
  ASSERT_FALSE(deformed.empty());
  v3::GetMeshRequest mesh_request;
  mesh_request.set_mesh_id(session_.mesh_id());
  mesh_request.set_include_geometry(true);
  v3::GetMeshResponse mesh;
  auto mc = Context();
  ASSERT_TRUE(stub_->GetMesh(mc.get(), mesh_request, &mesh).ok());
  // The reference: the same phantom, the map on the CPU at the server's
  // map resolution, the slice sampled in double, the same window.
  auto volume = ReadVolume(kPhantom, {});
  ASSERT_TRUE(volume.ok()) << volume.status();
  const VolumeGeometry& g = volume->geometry();
  auto map = CpuMap(mesh, deformed, g);
  ASSERT_TRUE(map.ok()) << map.status();
  for (const SliceCase& c : SliceCases(FromProto(Centre(volume_)))) {
    SCOPED_TRACE(c.name);
    v3::Frame frame;
    grpc::Status status = RenderSlice(c.spec, &frame);
    ASSERT_TRUE(status.ok()) << status.error_message();
    auto grid = MakeSliceGrid(c.plane, g);
    ASSERT_TRUE(grid.ok()) << grid.status();
    ASSERT_EQ(frame.width(), grid->width);
    ASSERT_EQ(frame.height(), grid->height);
    EXPECT_EQ(frame.encoding(), v3::ENCODING_PNG);
    EXPECT_NEAR(frame.slice().offset_mm(), glm::dot(grid->world_normal, grid->world_origin_mm),
                1e-6);
    EXPECT_NEAR(glm::length(FromProto(frame.slice().origin_mm()) - grid->world_origin_mm), 0.0, 1e-6);
    EXPECT_GT(frame.max_displacement_mm(), 1.0);
    const MipWindow window{40, 400};
    const std::vector<uint8_t> reference =
        SliceToRgba(SampleSliceCpu(*volume, &*map, *grid), grid->width, grid->height, window);
    const std::vector<uint8_t> at_rest =
        SliceToRgba(SampleSliceCpu(*volume, nullptr, *grid), grid->width, grid->height, window);
    const DecodedImage got = DecodeFramePng(frame.image());
    ASSERT_EQ(got.rgba.size(), reference.size());
    const GreyDifference diff = CompareGrey(got.rgba, reference, at_rest);
    const int64_t pixels = int64_t(grid->width) * grid->height;
    std::printf(
        "%s %dx%d: mean |grey difference| %.3f, %lld of %lld pixels over 12; drag moved the "
        "reference by %.3f\n",
        c.name, grid->width, grid->height, diff.mean, static_cast<long long>(diff.far),
        static_cast<long long>(pixels), diff.moved_mean);
    EXPECT_LT(diff.mean, 1.5);
    EXPECT_LE(diff.far, pixels / 100);
    // The reference itself moved: the drag shows in the slice.
    EXPECT_GT(diff.moved_mean, 2.0 * diff.mean + 0.2);
  }
}

TEST_F(RenderSliceTest, RenderSlice_DefaultPlaneFollowsTheGrabbedTissue) {
  v3::SliceSpec spec;
  spec.set_orientation(v3::SLICE_ORIENTATION_SAGITTAL);  // normal L: offset = world x
  v3::Frame before;
  ASSERT_TRUE(RenderSlice(spec, &before).ok());
  const glm::dvec3 world = FromProto(Centre(volume_));  // the grab point, world LPS
  EXPECT_NEAR(before.slice().offset_mm(), world.x, 1e-6);
  EXPECT_LT(before.slice().min_offset_mm(), before.slice().offset_mm());
  EXPECT_GT(before.slice().max_offset_mm(), before.slice().offset_mm());
  EXPECT_EQ(before.slice().cut_tets(), -1);
  GrabAndDrag(5.0);
  spec.set_overlay(true);
  v3::Frame after;
  ASSERT_TRUE(RenderSlice(spec, &after).ok());
  // The grabbed tissue moved 5 mm along world x (the drag is world LPS).
  EXPECT_NEAR(after.slice().offset_mm(), world.x + 5.0, 1e-6);
  EXPECT_GT(after.slice().cut_tets(), 0);
  EXPECT_NEAR(after.slice().window().width(), 400.0, 1e-9);  // the CT default
}

TEST_F(RenderSliceTest, RenderSlice_BadInputGetsClearStatusesAndTheServerGoesOn) {
  struct Bad {
    const char* name;
    v3::SliceSpec spec;
    grpc::StatusCode code;
    const char* says;
  };
  std::vector<Bad> bad;
  v3::SliceSpec unset;
  bad.push_back({"unset orientation", unset, grpc::INVALID_ARGUMENT, "slice.orientation"});
  bad.push_back({"NaN", Axial(std::nan("")), grpc::INVALID_ARGUMENT, "slice.at_mm"});
  bad.push_back({"outside", Axial(1e4), grpc::INVALID_ARGUMENT, "misses the volume"});
  v3::SliceSpec zero_normal;
  zero_normal.set_orientation(v3::SLICE_ORIENTATION_OBLIQUE);
  *zero_normal.mutable_normal() = V(0, 0, 0);
  bad.push_back({"zero normal", zero_normal, grpc::INVALID_ARGUMENT, "slice.normal"});
  v3::SliceSpec tiny = Axial(0);
  tiny.clear_at_mm();
  tiny.set_pixel_mm(1e-3);
  bad.push_back({"absurd size", tiny, grpc::INVALID_ARGUMENT, "pixels"});
  v3::SliceSpec inf_pixel = tiny;
  inf_pixel.set_pixel_mm(INFINITY);
  bad.push_back({"infinite pixel", inf_pixel, grpc::INVALID_ARGUMENT, "slice.pixel_mm"});
  v3::SliceSpec no_width = tiny;
  no_width.set_pixel_mm(0);
  no_width.mutable_window()->set_width(0);
  bad.push_back({"zero window", no_width, grpc::INVALID_ARGUMENT, "slice.window"});
  v3::SliceSpec landmark;
  landmark.set_orientation(v3::SLICE_ORIENTATION_AXIAL);
  landmark.set_at_landmark("no_such_organ");
  bad.push_back({"landmark", landmark, grpc::INVALID_ARGUMENT, "no_such_organ"});
  v3::SliceSpec both = Axial(0);
  both.set_at_landmark("x");
  bad.push_back({"two places", both, grpc::INVALID_ARGUMENT, "at most one"});
  for (const Bad& b : bad) {
    SCOPED_TRACE(b.name);
    v3::Frame frame;
    grpc::Status status = RenderSlice(b.spec, &frame);
    EXPECT_EQ(status.error_code(), b.code) << status.error_message();
    EXPECT_NE(status.error_message().find(b.says), std::string::npos) << status.error_message();
  }
  v3::Frame frame;
  EXPECT_EQ(RenderSlice(Axial(0), &frame, "ses-404").error_code(), grpc::NOT_FOUND);
  v3::RenderSliceRequest quality;
  quality.set_session_id(session_.session_id());
  *quality.mutable_slice() = landmark;
  quality.mutable_slice()->clear_at_landmark();
  quality.set_jpeg_quality(101);
  auto qc = Context();
  grpc::Status refused = stub_->RenderSlice(qc.get(), quality, &frame);
  EXPECT_EQ(refused.error_code(), grpc::INVALID_ARGUMENT);
  EXPECT_NE(refused.error_message().find("jpeg_quality"), std::string::npos);
  // A landmark of the phantom places the plane; the server is still there.
  ASSERT_GT(volume_.landmarks_size(), 0);
  landmark.set_at_landmark(volume_.landmarks(0).name());
  grpc::Status status = RenderSlice(landmark, &frame);
  ASSERT_TRUE(status.ok()) << status.error_message();
  EXPECT_NEAR(frame.slice().offset_mm(), volume_.landmarks(0).position_mm().z(), 1e-6);
}

TEST_F(RenderSliceTest, Interact_FramesCarryTheSlicesTheSettingsAskFor) {
  auto context = Context();
  auto stream = stub_->Interact(context.get());
  v3::InteractRequest first;
  first.set_session_id(session_.session_id());
  first.mutable_event()->set_sequence(1);
  v3::RenderSettings* settings = first.mutable_event()->mutable_settings();
  settings->set_width(96);
  settings->set_height(96);
  const std::pair<const char*, v3::SliceOrientation> views[] = {
      {"axial", v3::SLICE_ORIENTATION_AXIAL},
      {"coronal", v3::SLICE_ORIENTATION_CORONAL},
      {"sagittal", v3::SLICE_ORIENTATION_SAGITTAL}};
  for (const auto& [view, orientation] : views) {
    v3::SliceSpec* s = settings->add_slices();
    s->set_view(view);
    s->set_orientation(orientation);
  }
  ASSERT_TRUE(stream->Write(first));
  v3::Frame frame;
  ASSERT_TRUE(stream->Read(&frame));
  ASSERT_EQ(frame.slices_size(), 3);
  for (int i = 0; i < 3; ++i) {
    const v3::SliceImage& s = frame.slices(i);
    EXPECT_EQ(s.view(), views[i].first);
    EXPECT_EQ(s.geometry().orientation(), views[i].second);
    auto decoded =
        DecodeJpeg({reinterpret_cast<const uint8_t*>(s.image().data()), s.image().size()});
    ASSERT_TRUE(decoded.ok()) << decoded.status();
    EXPECT_EQ(decoded->width, s.width());
    EXPECT_EQ(decoded->height, s.height());
    EXPECT_GT(s.width(), 40);
  }
  // Scrolling: the axial slice moves to the asked position.
  const double lo = frame.slices(0).geometry().min_offset_mm();
  v3::InteractRequest scroll;
  scroll.mutable_event()->set_sequence(2);
  *scroll.mutable_event()->mutable_settings() = *settings;
  scroll.mutable_event()->mutable_settings()->mutable_slices(0)->set_at_mm(lo + 3.0);
  ASSERT_TRUE(stream->Write(scroll));
  bool scrolled = false;
  while (stream->Read(&frame)) {
    if (frame.last_sequence() < 2) continue;
    ASSERT_EQ(frame.slices_size(), 3);
    EXPECT_NEAR(frame.slices(0).geometry().offset_mm(), lo + 3.0, 1e-6);
    scrolled = true;
    break;
  }
  EXPECT_TRUE(scrolled);
  // Four slices are refused with the field named, ending the stream.
  v3::InteractRequest four;
  four.mutable_event()->set_sequence(3);
  *four.mutable_event()->mutable_settings() = *settings;
  *four.mutable_event()->mutable_settings()->add_slices() = settings->slices(0);
  ASSERT_TRUE(stream->Write(four));
  stream->WritesDone();
  while (stream->Read(&frame)) {
  }
  grpc::Status status = stream->Finish();
  EXPECT_EQ(status.error_code(), grpc::INVALID_ARGUMENT);
  EXPECT_NE(status.error_message().find("settings.slices"), std::string::npos)
      << status.error_message();
}

}  // namespace
}  // namespace vpm::service::testing
