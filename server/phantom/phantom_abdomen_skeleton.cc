// Skeleton of the abdomen phantom: vertebral column (T9 to S1 levels) and
// the lower ribs, world LPS mm, HU. Bone is a cortical shell (700 HU) around
// cancellous bone (300 HU), both above the 250 HU bone threshold.
#include <cmath>
#include <string>
#include <vector>

#include "server/phantom/phantom_abdomen.h"

namespace vpm::phantom {
namespace {

using glm::dvec2;
using glm::dvec3;

// Vertebrae repeat every 32 mm along z: a 23 mm body and a 9 mm disc.
// Level n has its body centred at z = 32 n: L2 at 0 (kidney level), L1 at
// 32, T12 at 64, T11 at 96, T10 at 128, L3 at -32, ...
constexpr double kVertebralPitchMm = 32.0;
constexpr double kBodyHalfHeightMm = 11.5;
constexpr int kLowestLevel = -6;
constexpr int kHighestLevel = 6;
constexpr double kSpineY = 40.0;        // vertebral body centre, mm posterior of the body centre
constexpr double kCanalY = 66.0;        // spinal canal centre
constexpr double kUnboundedMm = 1.0e4;  // "whole z range"

// Vertebral body semi-axes (mm): lumbar bodies grow caudally.
dvec2 BodySemiAxes(double z) { return {24.0 - 0.025 * z, 17.0 - 0.012 * z}; }

Primitive Bone(std::string name, ShapePtr shape, double cortex_mm) {
  return {std::move(name),
          std::move(shape),
          {{hu::kCorticalBone, 0.0}, {hu::kCancellousBone, cortex_mm}},
          false};
}

// Posterior elements of the vertebra centred at z = zc: pedicles, laminae,
// spinous process, transverse and articular processes.
ShapePtr PosteriorElements(double zc, bool thoracic) {
  std::vector<std::vector<TubeNode>> parts;
  for (const double s : {1.0, -1.0}) {
    parts.push_back(
        {{dvec3(s * 12.0, 53.0, zc + 3.0), 5.0}, {dvec3(s * 13.0, 64.0, zc + 3.0), 5.0}});
    parts.push_back({{dvec3(s * 13.0, 66.0, zc + 2.0), 4.0},
                     {dvec3(s * 9.0, 76.0, zc), 4.0},
                     {dvec3(0.0, 79.0, zc - 1.0), 4.0}});
    const double tip_x = thoracic ? 30.0 : 42.0;
    const double tip_y = thoracic ? 72.0 : 64.0;
    parts.push_back({{dvec3(s * 13.0, 62.0, zc + 2.0), 3.5}, {dvec3(s * tip_x, tip_y, zc), 3.5}});
    parts.push_back(
        {{dvec3(s * 16.0, 70.0, zc + 4.0), 4.0}, {dvec3(s * 18.0, 72.0, zc + 16.0), 3.5}});
    parts.push_back(
        {{dvec3(s * 12.0, 74.0, zc - 4.0), 4.0}, {dvec3(s * 13.0, 76.0, zc - 15.0), 3.5}});
  }
  // Spinous process: a plate, two capsules stacked in z, sloping caudally.
  parts.push_back({{dvec3(0.0, 78.0, zc - 2.0), 4.5}, {dvec3(0.0, 100.0, zc - 10.0), 4.0}});
  parts.push_back({{dvec3(0.0, 78.0, zc + 4.0), 4.0}, {dvec3(0.0, 98.0, zc - 4.0), 3.5}});
  return MakeTube(parts);
}

void AddVertebralColumn(Scene& scene) {
  scene.primitives.push_back(
      {"spinal_canal",
       MakeEllipticPrism(dvec2(0.0, kCanalY), dvec2(11.0, 9.0), -kUnboundedMm, kUnboundedMm, 0.0),
       {{hu::kSpinalCanal, 0.0}},
       false});
  for (int level = kLowestLevel; level <= kHighestLevel; ++level) {
    const double zc = kVertebralPitchMm * level;
    const dvec2 semi = BodySemiAxes(zc);
    const std::string name = "vertebra_" + std::to_string(level);
    // The disc below this body, slightly overlapping both neighbours (which
    // are painted over it).
    const double disc_top = zc - kBodyHalfHeightMm + 1.0;
    const double disc_bottom = zc - kVertebralPitchMm + kBodyHalfHeightMm - 1.0;
    scene.primitives.push_back(
        {"disc_below_" + name,
         MakeEllipticPrism(dvec2(0.0, kSpineY), semi - 0.5, disc_bottom, disc_top, 1.0),
         {{hu::kDisc, 0.0}},
         false});
    scene.primitives.push_back(
        Bone(name + "_body",
             MakeEllipticPrism(dvec2(0.0, kSpineY), semi, zc - kBodyHalfHeightMm,
                               zc + kBodyHalfHeightMm, 2.0),
             kVertebralCortexMm));
    scene.primitives.push_back(
        Bone(name + "_arch", PosteriorElements(zc, level >= 2), kVertebralCortexMm));
  }
}

// One rib from the vertebra at z = zc around the body wall to angle
// end_angle (radians from straight posterior), descending as it goes.
std::vector<TubeNode> Rib(double side, double zc, double end_angle) {
  constexpr double kRadiusMm = 5.0;
  std::vector<TubeNode> nodes = {{dvec3(side * 19.0, 56.0, zc + 2.0), 4.0},
                                 {dvec3(side * 38.0, 70.0, zc), kRadiusMm}};
  // Beyond the rib angle the rib follows an ellipse inside the body wall.
  constexpr double kStartAngle = 0.45;
  constexpr double kStep = 0.15;
  for (double angle = kStartAngle; angle < end_angle + 1e-9; angle += kStep) {
    const double drop = 8.0 + 30.0 * (angle - kStartAngle);
    nodes.push_back({dvec3(side * 142.0 * std::sin(angle), 5.0 + 88.0 * std::cos(angle), zc - drop),
                     kRadiusMm});
  }
  return nodes;
}

void AddRibs(Scene& scene) {
  struct RibLevel {
    int level;
    double end_angle;
  };
  // Ribs 12 (short, ends posterolaterally) up to 9 (reaches anterolaterally).
  constexpr RibLevel kRibs[] = {{2, 1.15}, {3, 1.75}, {4, 2.25}, {5, 2.6}};
  for (const RibLevel& rib : kRibs) {
    for (const double side : {1.0, -1.0}) {
      const std::string name =
          std::string(side > 0 ? "left" : "right") + "_rib_" + std::to_string(14 - rib.level);
      scene.primitives.push_back(Bone(
          name, MakeTube({Rib(side, kVertebralPitchMm * rib.level, rib.end_angle)}), kRibCortexMm));
    }
  }
}

}  // namespace

void AddAbdomenSkeleton(Scene& scene) {
  AddVertebralColumn(scene);
  AddRibs(scene);
}

}  // namespace vpm::phantom
