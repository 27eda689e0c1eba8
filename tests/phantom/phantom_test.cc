#include "server/phantom/phantom.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "server/phantom/phantom_abdomen.h"
#include "server/phantom/phantom_noise.h"

namespace vpm {
namespace {

Volume MakeOrDie(const std::string& spec) {
  Result<Volume> v = MakePhantom(spec, VolumeLimits{});
  EXPECT_TRUE(v.ok()) << spec << ": " << v.status();
  return *std::move(v);
}

Volume MakeOrDie(const PhantomSpec& spec) {
  Result<Volume> v = MakePhantomFromSpec(spec, VolumeLimits{});
  EXPECT_TRUE(v.ok()) << v.status();
  return *std::move(v);
}

glm::dvec3 LandmarkMm(const Volume& v, const std::string& name) {
  for (const Landmark& l : v.landmarks()) {
    if (l.name == name) return l.position_mm;
  }
  ADD_FAILURE() << "no landmark " << name;
  return glm::dvec3(0.0);
}

// Mean of the voxels whose centres lie within radius_mm of p_mm (physical
// voxel space); the nearest voxel alone where none does.
double MeanNear(const Volume& v, const glm::dvec3& p_mm, double radius_mm) {
  const VolumeGeometry& g = v.geometry();
  const glm::dvec3 lo = glm::floor(g.PhysicalToIndex(p_mm - radius_mm));
  const glm::dvec3 hi = glm::ceil(g.PhysicalToIndex(p_mm + radius_mm));
  double sum = 0.0;
  int count = 0;
  for (auto k = static_cast<int64_t>(lo.z); k <= static_cast<int64_t>(hi.z); ++k) {
    for (auto j = static_cast<int64_t>(lo.y); j <= static_cast<int64_t>(hi.y); ++j) {
      for (auto i = static_cast<int64_t>(lo.x); i <= static_cast<int64_t>(hi.x); ++i) {
        const glm::dvec3 c = g.IndexToPhysical(glm::dvec3(i, j, k));
        if (glm::length(c - p_mm) > radius_mm) continue;
        sum += v.AtClamped(i, j, k);
        ++count;
      }
    }
  }
  if (count > 0) return sum / count;
  const glm::dvec3 n = glm::round(g.PhysicalToIndex(p_mm));
  return v.AtClamped(static_cast<int64_t>(n.x), static_cast<int64_t>(n.y),
                     static_cast<int64_t>(n.z));
}

struct Moments {
  double mean = 0.0;
  double sigma = 0.0;
};

// Mean and standard deviation of the voxels in the index box [lo, hi).
Moments BoxMoments(const Volume& v, std::array<int64_t, 3> lo, std::array<int64_t, 3> hi) {
  double sum = 0.0;
  double sum2 = 0.0;
  int64_t n = 0;
  for (int64_t k = lo[2]; k < hi[2]; ++k) {
    for (int64_t j = lo[1]; j < hi[1]; ++j) {
      for (int64_t i = lo[0]; i < hi[0]; ++i) {
        const double x = v.At(i, j, k);
        sum += x;
        sum2 += x * x;
        ++n;
      }
    }
  }
  const double mean = sum / static_cast<double>(n);
  return {mean, std::sqrt(sum2 / static_cast<double>(n) - mean * mean)};
}

// --- Shapes -------------------------------------------------------------------

TEST(PhantomShapes, EllipsoidDistanceIsExactOnItsAxes) {
  const glm::dmat3 frame(glm::dvec3(0, 1, 0), glm::dvec3(-1, 0, 0), glm::dvec3(0, 0, 1));
  const phantom::ShapePtr e =
      phantom::MakeEllipsoid(glm::dvec3(10, 20, 30), glm::dvec3(40, 20, 10), frame);
  // Local axis 0 (semi-axis 40 mm) points along world +y.
  EXPECT_NEAR(e->Distance(glm::dvec3(10, 20 + 43, 30)), 3.0, 1e-9);
  EXPECT_NEAR(e->Distance(glm::dvec3(10 - 18, 20, 30)), -2.0, 1e-9);
  EXPECT_NEAR(e->Distance(glm::dvec3(10, 20, 30 + 10)), 0.0, 1e-9);
  EXPECT_LT(e->Distance(glm::dvec3(10, 20, 30)), 0.0);
  const phantom::Box3 box = e->Bounds();
  EXPECT_NEAR(box.hi.y, 60.0, 1e-9);
  EXPECT_NEAR(box.hi.x, 30.0, 1e-9);
}

TEST(PhantomShapes, TubeRadiusFollowsItsNodes) {
  const phantom::ShapePtr tube =
      phantom::MakeTube({{{glm::dvec3(0, 0, 0), 2.0}, {glm::dvec3(0, 0, 10), 4.0}}});
  EXPECT_NEAR(tube->Distance(glm::dvec3(5, 0, 5)), 5.0 - 3.0, 1e-9);
  EXPECT_NEAR(tube->Distance(glm::dvec3(0, 0, -3)), 1.0, 1e-9);  // round cap
  EXPECT_NEAR(tube->Distance(glm::dvec3(0, 0, 10)), -4.0, 1e-9);
  const std::vector<glm::dvec3> line = {glm::dvec3(0), glm::dvec3(3, 0, 0), glm::dvec3(3, 4, 0)};
  EXPECT_DOUBLE_EQ(phantom::PolylineLength(line), 7.0);
  EXPECT_EQ(phantom::PointAtArcLength(line, 5.0), glm::dvec3(3, 2, 0));
  EXPECT_EQ(phantom::PointAtArcLength(line, 99.0), glm::dvec3(3, 4, 0));
}

// Row evaluation culls per row; it must agree with point evaluation wherever
// the distance is within reach.
TEST(PhantomShapes, RowDistanceMatchesPointDistanceWithinReach) {
  using phantom::MakeDifference;
  const phantom::ShapePtr ellipsoid =
      phantom::MakeEllipsoid(glm::dvec3(5, -3, 2), glm::dvec3(20, 12, 30));
  const std::vector<phantom::ShapePtr> shapes = {
      ellipsoid,
      phantom::MakeTube({{{glm::dvec3(-30, 0, -20), 3.0},
                          {glm::dvec3(0, 5, 0), 5.0},
                          {glm::dvec3(25, -10, 20), 2.0}},
                         {{glm::dvec3(10, 10, 10), 6.0}}}),
      phantom::MakeEllipticPrism(glm::dvec2(2, 3), glm::dvec2(15, 9), -10, 12, 2.0),
      MakeDifference(phantom::MakeInset(ellipsoid, 4.0),
                     phantom::MakeEllipsoid(glm::dvec3(20, -3, 2), glm::dvec3(10, 8, 12))),
      phantom::MakeInset(
          phantom::MakeTube({{{glm::dvec3(-20, 0, 0), 8.0}, {glm::dvec3(20, 0, 0), 8.0}}}), 5.0),
      phantom::MakeIntersection(ellipsoid,
                                phantom::MakeHalfSpace(glm::dvec3(0, 1, 0), glm::dvec3(0, 1, 0))),
  };
  constexpr double kReach = 3.0;
  std::vector<float> row_distance(120);
  for (const phantom::ShapePtr& shape : shapes) {
    for (double z = -36.0; z <= 36.0; z += 3.7) {
      for (double y = -24.0; y <= 24.0; y += 2.9) {
        const phantom::SampleRow row{-45.0, 0.75, y, z};
        shape->RowDistance(row, kReach, row_distance);
        for (size_t n = 0; n < row_distance.size(); ++n) {
          const double d = shape->Distance(row.Point(n));
          if (std::abs(d) < kReach) {
            ASSERT_NEAR(row_distance[n], d, 1e-4) << "y " << y << " z " << z << " n " << n;
          } else if (d > 0.0) {
            ASSERT_GE(row_distance[n], kReach - 1e-4);
          } else {
            ASSERT_LE(row_distance[n], -kReach + 1e-4);
          }
        }
      }
    }
  }
}

// --- Spec syntax --------------------------------------------------------------

TEST(PhantomNames, ListsAbdomen) {
  const std::vector<std::string> names = PhantomNames();
  EXPECT_NE(std::find(names.begin(), names.end(), "abdomen"), names.end());
}

TEST(ParsePhantomSpec, ReadsEveryParameter) {
  Result<PhantomSpec> spec =
      ParsePhantomSpec("abdomen?dims=10,20,30&spacing=1.5,2,2.5&seed=7&noise=0");
  ASSERT_TRUE(spec.ok()) << spec.status();
  EXPECT_EQ(spec->name, "abdomen");
  EXPECT_EQ(spec->dims, (std::array<int64_t, 3>{10, 20, 30}));
  ASSERT_TRUE(spec->spacing_mm.has_value());
  EXPECT_EQ(*spec->spacing_mm, glm::dvec3(1.5, 2.0, 2.5));
  EXPECT_EQ(spec->seed, 7u);
  EXPECT_EQ(spec->noise_sigma_hu, 0.0);

  spec = ParsePhantomSpec("abdomen");
  ASSERT_TRUE(spec.ok());
  EXPECT_EQ(spec->dims, (std::array<int64_t, 3>{256, 256, 256}));
  EXPECT_FALSE(spec->spacing_mm.has_value());
  EXPECT_EQ(spec->seed, kDefaultPhantomSeed);
  EXPECT_EQ(spec->noise_sigma_hu, 10.0);

  spec = ParsePhantomSpec("abdomen?size=96");
  ASSERT_TRUE(spec.ok());
  EXPECT_EQ(spec->dims, (std::array<int64_t, 3>{96, 96, 96}));
}

TEST(Phantom, RejectsBadSpecsWithTheRightCode) {
  struct Case {
    const char* spec;
    absl::StatusCode code;
    const char* message_names;  // the message must contain this
  };
  const Case kCases[] = {
      {"liver", absl::StatusCode::kInvalidArgument, "abdomen"},
      {"", absl::StatusCode::kInvalidArgument, "abdomen"},
      {"abdomen?size=0", absl::StatusCode::kInvalidArgument, "size"},
      {"abdomen?size=-3", absl::StatusCode::kInvalidArgument, "size"},
      {"abdomen?size=abc", absl::StatusCode::kInvalidArgument, "size"},
      {"abdomen?size=", absl::StatusCode::kInvalidArgument, "size"},
      {"abdomen?size", absl::StatusCode::kInvalidArgument, "size"},
      {"abdomen?dims=1,2", absl::StatusCode::kInvalidArgument, "dims"},
      {"abdomen?dims=1,2,x", absl::StatusCode::kInvalidArgument, "dims"},
      {"abdomen?dims=4,4,0", absl::StatusCode::kInvalidArgument, "dims"},
      {"abdomen?spacing=NaN,1,1", absl::StatusCode::kInvalidArgument, "spacing"},
      {"abdomen?spacing=1,inf,1", absl::StatusCode::kInvalidArgument, "spacing"},
      {"abdomen?spacing=1,1,-2", absl::StatusCode::kInvalidArgument, "spacing"},
      {"abdomen?spacing=1e-9,1,1", absl::StatusCode::kInvalidArgument, "spacing"},
      {"abdomen?spacing=1,1,1e300", absl::StatusCode::kInvalidArgument, "spacing"},
      {"abdomen?noise=1e30", absl::StatusCode::kInvalidArgument, "noise"},
      {"abdomen?seed=-1", absl::StatusCode::kInvalidArgument, "seed"},
      {"abdomen?noise=-5", absl::StatusCode::kInvalidArgument, "noise"},
      {"abdomen?noise=nan", absl::StatusCode::kInvalidArgument, "noise"},
      {"abdomen?colour=red", absl::StatusCode::kInvalidArgument, "spacing"},  // lists valid ones
      {"abdomen?size=8&size=8", absl::StatusCode::kInvalidArgument, "size"},
      {"abdomen?size=8&dims=8,8,8", absl::StatusCode::kInvalidArgument, "dims"},
      // Over the voxel cap: refused before any allocation (4e15 bytes here).
      {"abdomen?size=100000", absl::StatusCode::kResourceExhausted, "cap"},
      {"abdomen?dims=600,600,600", absl::StatusCode::kResourceExhausted, "cap"},
  };
  for (const Case& c : kCases) {
    const Result<Volume> v = MakePhantom(c.spec, VolumeLimits{});
    EXPECT_EQ(v.status().code(), c.code) << c.spec << ": " << v.status();
    EXPECT_NE(v.status().message().find(c.message_names), absl::string_view::npos)
        << c.spec << ": " << v.status();
  }
  VolumeLimits tiny;
  tiny.max_volume_bytes = 1000 * 4;  // 1000 float voxels
  EXPECT_EQ(MakePhantom("abdomen?size=16", tiny).status().code(),
            absl::StatusCode::kResourceExhausted);
}

// --- Determinism and noise ------------------------------------------------------

TEST(Phantom, SameSpecGivesIdenticalBytesWhateverTheThreadCount) {
  PhantomSpec spec = *ParsePhantomSpec("abdomen?dims=45,38,33");  // odd rows: pairs straddle rows
  spec.threads = 1;
  const Volume one = MakeOrDie(spec);
  spec.threads = 3;
  const Volume three = MakeOrDie(spec);
  const Volume again = MakeOrDie("abdomen?dims=45,38,33");
  ASSERT_EQ(one.voxels().floats().size(), three.voxels().floats().size());
  EXPECT_EQ(std::memcmp(one.voxels().floats().data(), three.voxels().floats().data(), one.voxels().floats().size_bytes()), 0);
  EXPECT_EQ(std::memcmp(one.voxels().floats().data(), again.voxels().floats().data(), one.voxels().floats().size_bytes()), 0);
}

TEST(Phantom, SeedChangesOnlyTheNoise) {
  const Volume a = MakeOrDie("abdomen?size=40&seed=1");
  const Volume b = MakeOrDie("abdomen?size=40&seed=2");
  double sum2 = 0.0;
  for (size_t n = 0; n < a.voxels().floats().size(); ++n) {
    const double d = a.voxels().floats()[n] - b.voxels().floats()[n];
    sum2 += d * d;
  }
  // The difference of two independent N(0, 10^2) fields has sigma 10 * sqrt(2).
  EXPECT_NEAR(std::sqrt(sum2 / static_cast<double>(a.voxels().floats().size())), 10.0 * std::sqrt(2.0), 0.5);
  const Volume quiet_a = MakeOrDie("abdomen?size=40&seed=1&noise=0");
  const Volume quiet_b = MakeOrDie("abdomen?size=40&seed=2&noise=0");
  EXPECT_EQ(
      std::memcmp(quiet_a.voxels().floats().data(), quiet_b.voxels().floats().data(), quiet_a.voxels().floats().size_bytes()),
      0);
}

TEST(Phantom, NoiseSigmaMatchesTheSpecInUniformRegions) {
  const Volume v = MakeOrDie("abdomen?size=64");
  // An 8^3 block of air in a corner, and the liver interior.
  const Moments air = BoxMoments(v, {0, 0, 0}, {8, 8, 8});
  EXPECT_NEAR(air.mean, -1000.0, 2.0);
  EXPECT_NEAR(air.sigma, 10.0, 2.0);
  const glm::dvec3 liver = v.geometry().PhysicalToIndex(LandmarkMm(v, "liver"));
  const std::array<int64_t, 3> c{std::llround(liver.x), std::llround(liver.y),
                                 std::llround(liver.z)};
  const Moments organ =
      BoxMoments(v, {c[0] - 2, c[1] - 2, c[2] - 2}, {c[0] + 3, c[1] + 3, c[2] + 3});
  EXPECT_NEAR(organ.mean, phantom::hu::kLiver, 5.0);
  EXPECT_NEAR(organ.sigma, 10.0, 2.5);  // 125 voxels

  const Volume loud = MakeOrDie("abdomen?size=64&noise=25");
  EXPECT_NEAR(BoxMoments(loud, {0, 0, 0}, {8, 8, 8}).sigma, 25.0, 4.0);
  const Volume quiet = MakeOrDie("abdomen?size=64&noise=0");
  EXPECT_EQ(BoxMoments(quiet, {0, 0, 0}, {8, 8, 8}).sigma, 0.0);
}

TEST(GaussianNoise, RowsMatchTheCounterWhereverTheyStart) {
  std::vector<float> whole(101, 0.0f);
  phantom::AddGaussianNoise(42, 7, 1.0f, whole);
  for (size_t split : {0u, 1u, 2u, 50u, 51u}) {
    std::vector<float> parts(101, 0.0f);
    phantom::AddGaussianNoise(42, 7, 1.0f, std::span<float>(parts).first(split));
    phantom::AddGaussianNoise(42, 7 + split, 1.0f, std::span<float>(parts).subspan(split));
    EXPECT_EQ(parts, whole) << "split at " << split;
  }
  for (size_t n = 0; n < whole.size(); ++n) {
    EXPECT_EQ(whole[n], phantom::GaussianDeviate(42, 7 + n));
  }
}

TEST(GaussianNoise, IsStandardNormal) {
  double sum = 0.0;
  double sum2 = 0.0;
  int beyond_two_sigma = 0;
  constexpr int kCount = 200000;
  for (int n = 0; n < kCount; ++n) {
    const double x = phantom::GaussianDeviate(3, static_cast<uint64_t>(n));
    sum += x;
    sum2 += x * x;
    beyond_two_sigma += std::abs(x) > 2.0;
  }
  EXPECT_NEAR(sum / kCount, 0.0, 0.01);
  EXPECT_NEAR(sum2 / kCount, 1.0, 0.01);
  EXPECT_NEAR(static_cast<double>(beyond_two_sigma) / kCount, 0.0455, 0.003);
}

// --- Geometry, landmarks, tissues -----------------------------------------------

TEST(Phantom, DefaultHasFixedFieldOfViewAndTissuesAtLandmarks) {
  const auto start = std::chrono::steady_clock::now();
  const Volume v = MakeOrDie("abdomen");
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  RecordProperty("generation_ms", static_cast<int>(seconds * 1000.0));
  std::printf("phantom:abdomen 256^3 generated in %.3f s\n", seconds);

  const VolumeGeometry& g = v.geometry();
  EXPECT_EQ(g.dims, (std::array<int64_t, 3>{256, 256, 256}));
  EXPECT_DOUBLE_EQ(g.spacing_mm.x, 380.0 / 256.0);
  EXPECT_DOUBLE_EQ(g.spacing_mm.y, 380.0 / 256.0);
  EXPECT_DOUBLE_EQ(g.spacing_mm.z, 240.0 / 256.0);
  EXPECT_EQ(g.direction, glm::dmat3(1.0));
  // Voxel (0, 0, 0) at world -field of view / 2: the body centre is mid-box.
  EXPECT_EQ(g.origin_mm, glm::dvec3(-190.0, -190.0, -120.0));
  EXPECT_EQ(v.source(), "phantom:abdomen");

  struct Expect {
    const char* landmark;
    double radius_mm;
    double lo_hu;
    double hi_hu;
  };
  const Expect kExpect[] = {
      {"left_renal_artery", 1.8, 150.0, 250.0},
      {"right_renal_artery", 1.8, 150.0, 250.0},
      {"aorta", 4.0, 180.0, 240.0},
      {"vertebral_body", 4.0, 200.0, 400.0},
      {"left_kidney_center", 3.0, 30.0, 100.0},
      {"right_kidney_center", 3.0, 30.0, 100.0},
      {"liver", 4.0, 45.0, 75.0},
      {"spleen", 4.0, 35.0, 65.0},
  };
  for (const Expect& e : kExpect) {
    const double mean = MeanNear(v, LandmarkMm(v, e.landmark), e.radius_mm);
    EXPECT_GE(mean, e.lo_hu) << e.landmark;
    EXPECT_LE(mean, e.hi_hu) << e.landmark;
  }
  for (const Landmark& l : v.landmarks()) EXPECT_FALSE(l.description.empty()) << l.name;

  // Kidney surface: cortex 3 mm inside (towards the centre), fat 7 mm outside.
  const glm::dvec3 surface = LandmarkMm(v, "left_kidney_surface");
  const glm::dvec3 inward = glm::normalize(LandmarkMm(v, "left_kidney_center") - surface);
  const double cortex = MeanNear(v, surface + 3.0 * inward, 1.5);
  EXPECT_GE(cortex, 130.0);
  EXPECT_LE(cortex, 200.0);
  EXPECT_LT(MeanNear(v, surface - 7.0 * inward, 2.0), -40.0);
  EXPECT_LT(BoxMoments(v, {0, 0, 0}, {4, 4, 4}).mean, -900.0);  // air at a corner
}

TEST(Phantom, BoneExceedsThresholdButNoVesselOrKidneyDoes) {
  const Volume v = MakeOrDie("abdomen?size=96");
  const VolumeGeometry& g = v.geometry();
  int64_t bone = 0;
  for (float x : v.voxels().floats()) bone += x >= 250.0f;
  EXPECT_GT(bone, v.geometry().voxel_count() / 200);  // over 0.5% of the box is bone
  EXPECT_GT(MeanNear(v, LandmarkMm(v, "vertebral_body"), 6.0), 250.0);

  const phantom::AbdomenAnatomy anatomy = phantom::MakeAbdomenAnatomy();
  for (const phantom::Vessel& vessel : anatomy.vessels) {
    std::vector<glm::dvec3> points;
    for (const phantom::TubeNode& node : vessel.centreline) points.push_back(node.point_mm);
    const double length = phantom::PolylineLength(points);
    for (double s = 0.0; s <= length; s += 2.0) {
      const glm::dvec3 p = g.WorldToPhysical(phantom::PointAtArcLength(points, s));
      if (glm::any(glm::lessThan(p, glm::dvec3(0.0))) ||
          glm::any(glm::greaterThan(p, g.extent_mm()))) {
        continue;
      }
      ASSERT_LT(MeanNear(v, p, 2.0), 250.0) << vessel.name << " at " << s << " mm";
    }
  }
  for (const auto* kidney : {&anatomy.left_kidney, &anatomy.right_kidney}) {
    for (double t = -0.8; t <= 0.8; t += 0.1) {
      const glm::dvec3 p = kidney->center_mm + t * kidney->semi_axes_mm.z * kidney->frame[2];
      EXPECT_LT(MeanNear(v, g.WorldToPhysical(p), 2.0), 250.0);
    }
  }
}

TEST(Phantom, LandmarksKeepTheirPlaceAcrossSizes) {
  const Volume small = MakeOrDie("abdomen?size=64");
  const Volume large = MakeOrDie("abdomen?size=128");
  ASSERT_EQ(small.landmarks().size(), large.landmarks().size());
  ASSERT_GE(small.landmarks().size(), 8u);
  for (size_t n = 0; n < small.landmarks().size(); ++n) {
    const Landmark& a = small.landmarks()[n];
    const Landmark& b = large.landmarks()[n];
    ASSERT_EQ(a.name, b.name);
    // Same anatomy in world space, and the same physical voxel position,
    // since the field of view and its corner do not depend on dims.
    EXPECT_NEAR(glm::distance(small.geometry().PhysicalToWorld(a.position_mm),
                              large.geometry().PhysicalToWorld(b.position_mm)),
                0.0, 1e-9)
        << a.name;
    EXPECT_NEAR(glm::distance(a.position_mm, b.position_mm), 0.0, 1e-9) << a.name;
    // And the index of the nearest voxel scales with the size.
    const glm::dvec3 ia = small.geometry().PhysicalToIndex(a.position_mm);
    const glm::dvec3 ib = large.geometry().PhysicalToIndex(b.position_mm);
    EXPECT_NEAR(glm::distance(2.0 * ia, ib), 0.0, 1e-9) << a.name;
  }
}

TEST(Phantom, AnisotropicDimsAndSpacingShowTheSameAnatomy) {
  const Volume v = MakeOrDie("abdomen?dims=80,60,40");
  EXPECT_EQ(v.dims(), (std::array<int64_t, 3>{80, 60, 40}));
  EXPECT_DOUBLE_EQ(v.spacing_mm().x, 380.0 / 80.0);
  EXPECT_DOUBLE_EQ(v.spacing_mm().y, 380.0 / 60.0);
  EXPECT_DOUBLE_EQ(v.spacing_mm().z, 240.0 / 40.0);

  const Volume w = MakeOrDie("abdomen?dims=96,80,48&spacing=4,4.5,5");
  EXPECT_EQ(w.spacing_mm(), glm::dvec3(4.0, 4.5, 5.0));
  const Volume reference = MakeOrDie("abdomen?size=64");
  for (const Volume* vol : {&v, &w}) {
    const VolumeGeometry& g = vol->geometry();
    const glm::dvec3 fov = glm::dvec3(g.dims[0], g.dims[1], g.dims[2]) * g.spacing_mm;
    EXPECT_NEAR(glm::distance(g.origin_mm, -0.5 * fov), 0.0, 1e-9);
    for (const Landmark& l : vol->landmarks()) {
      const glm::dvec3 expected =
          reference.geometry().PhysicalToWorld(LandmarkMm(reference, l.name));
      EXPECT_NEAR(glm::distance(g.PhysicalToWorld(l.position_mm), expected), 0.0, 1e-9) << l.name;
    }
    // Coarse voxels still see bone in the vertebral body and air in a corner.
    EXPECT_GT(MeanNear(*vol, LandmarkMm(*vol, "vertebral_body"), 5.0), 200.0);
    EXPECT_LT(vol->At(0, 0, 0), -900.0f);
  }
}

}  // namespace
}  // namespace vpm
