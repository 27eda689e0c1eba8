// Anatomy of the abdomen phantom: body wall, organs, kidneys and vessels
// (world LPS mm, HU). The skeleton is in phantom_abdomen_skeleton.cc.
#include "server/phantom/phantom_abdomen.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <span>
#include <utility>

#include "server/phantom/phantom_noise.h"

namespace vpm::phantom {
namespace {

using glm::dvec2;
using glm::dvec3;

constexpr double kDeg = std::numbers::pi / 180.0;

// --- Body cross-section (z-independent) ------------------------------------

// Superellipse |x/ax|^2.5 + |y/ay|^2.5 <= 1 with a different y semi-axis in front
// (anterior, y < 0) and behind (posterior, y > 0). Semi-axes in mm.
struct BodyContour {
  double ax;
  double ay_anterior;
  double ay_posterior;

  // The contour moved inwards by (lateral, anterior, posterior) mm.
  constexpr BodyContour Inset(double lateral, double anterior, double posterior) const {
    return {ax - lateral, ay_anterior - anterior, ay_posterior - posterior};
  }
  bool Contains(double x, double y) const {
    const double ay = y < 0.0 ? ay_anterior : ay_posterior;
    return Power2_5(std::abs(x) / ax) + Power2_5(std::abs(y) / ay) <= 1.0;
  }
  // t^2.5, the superellipse exponent: a little boxier than an ellipse.
  static double Power2_5(double t) { return t * t * std::sqrt(t); }
};

// Skin surface: 330 mm wide, 243 mm anteroposterior, flatter at the back.
// Inwards: skin 2.5 mm, subcutaneous fat 16 / 20 / 14 mm and wall muscle
// 12 / 10 / 10 mm (lateral / anterior / posterior), then the cavity.
constexpr BodyContour kSkin{165.0, 125.0, 118.0};
constexpr double kSkinMm = 2.5;
constexpr BodyContour kFatOuter = kSkin.Inset(kSkinMm, kSkinMm, kSkinMm);
constexpr BodyContour kMuscleOuter = kFatOuter.Inset(16.0, 20.0, 14.0);
constexpr BodyContour kCavity = kMuscleOuter.Inset(12.0, 10.0, 10.0);

// Posterior parietal peritoneum (mm): bowel lies in front of it, the
// retroperitoneal fat (kidneys, great vessels) behind it. Bowel loops thin
// out over kBowelFadeMm on either side of it instead of ending on a line.
double PeritoneumY(double x) { return -25.0 + 60.0 * (x / 120.0) * (x / 120.0); }
constexpr double kBowelFadeMm = 20.0;

CrossSectionSample BodyCrossSection(double x, double y) {
  // Nested contours, innermost first: most points are in the cavity.
  if (kCavity.Contains(x, y)) return {hu::kFat, y < PeritoneumY(x) + kBowelFadeMm, true};
  if (kMuscleOuter.Contains(x, y)) return {hu::kMuscle, false, false};
  if (kFatOuter.Contains(x, y)) return {hu::kSubcutaneousFat, false, false};
  if (kSkin.Contains(x, y)) return {hu::kSkin, false, false};
  return {hu::kAir, false, false};
}

// Bowel loops in mesenteric fat: two octaves of gradient noise (cells 36 and
// 14 mm) thresholded, with an edge blended over the voxel's blend width. The
// threshold makes most of the peritoneal space bowel, and rises across the
// peritoneum so that loops thin out towards the retroperitoneum.
class BowelTexture {
 public:
  void operator()(const SampleRow& row, double blend_width_mm, std::span<float> out) const {
    std::vector<float> fine(out.size());
    coarse_.Row(row.x0_mm, row.dx_mm, row.y_mm, row.z_mm, out);
    fine_.Row(row.x0_mm, row.dx_mm, row.y_mm, row.z_mm, fine);
    // The field changes by about 0.07 per mm, so (field - threshold) / 0.07
    // approximates a signed distance in mm.
    constexpr double kThreshold = -0.08;
    constexpr double kMmPerUnit = 1.0 / 0.07;
    const double inv_width = 1.0 / blend_width_mm;
    for (size_t n = 0; n < out.size(); ++n) {
      const double x = row.x0_mm + static_cast<double>(n) * row.dx_mm;
      const double depth = (row.y_mm - PeritoneumY(x) + kBowelFadeMm) / (2.0 * kBowelFadeMm);
      const double t = std::clamp(depth, 0.0, 1.0);
      const double threshold = kThreshold + 0.9 * t * t * (3.0 - 2.0 * t);
      const double field = out[n] + 0.5 * fine[n];
      const double coverage =
          std::clamp(0.5 + (field - threshold) * kMmPerUnit * inv_width, 0.0, 1.0);
      out[n] = static_cast<float>(hu::kFat + coverage * (hu::kBowel - hu::kFat));
    }
  }

 private:
  GradientNoise coarse_{0xB0E1ull, 36.0};
  GradientNoise fine_{0xB0E2ull, 14.0};
};

// --- Organs -----------------------------------------------------------------

Primitive Solid(std::string name, ShapePtr shape, float tissue_hu, bool clip = false) {
  return {std::move(name), std::move(shape), {{tissue_hu, 0.0}}, clip};
}

glm::dmat3 RotationZ(double degrees) {
  const double c = std::cos(degrees * kDeg);
  const double s = std::sin(degrees * kDeg);
  return glm::dmat3(dvec3(c, s, 0.0), dvec3(-s, c, 0.0), dvec3(0.0, 0.0, 1.0));
}

void AddSolidOrgans(Scene& scene, const AbdomenAnatomy& a) {
  // Liver: right lobe and a left lobe reaching across the midline in front
  // of the stomach, clipped by the abdominal wall.
  ShapePtr liver = MakeUnion(MakeEllipsoid(dvec3(-72.0, 5.0, 80.0), dvec3(72.0, 70.0, 72.0)),
                             MakeEllipsoid(dvec3(0.0, -52.0, 92.0), dvec3(58.0, 32.0, 36.0)));
  // Stomach: fluid with an anterior (non-dependent, supine) gas cap.
  ShapePtr stomach =
      MakeEllipsoid(dvec3(45.0, -40.0, 82.0), dvec3(42.0, 32.0, 40.0), RotationZ(-20.0));
  scene.primitives.push_back(
      {"stomach", stomach, {{hu::kBowelWall, 0.0}, {hu::kLumenFluid, 4.0}}, true});
  scene.primitives.push_back(
      Solid("stomach_gas",
            MakeIntersection(MakeInset(stomach, 4.0),
                             MakeHalfSpace(dvec3(0.0, -52.0, 0.0), dvec3(0.0, 1.0, 0.0))),
            hu::kAir, true));
  scene.primitives.push_back(Solid("liver", liver, hu::kLiver, true));
  scene.primitives.push_back(
      Solid("spleen", MakeEllipsoid(a.spleen_mm, dvec3(24.0, 55.0, 45.0), RotationZ(-30.0)),
            hu::kSpleen, true));
  // Colon: ascending (right), transverse (anterior, sagging), descending
  // (left); wall 3 mm, fluid contents, gas in front of y = -55 mm (supine).
  ShapePtr colon = MakeTube({{{dvec3(-98.0, -5.0, -140.0), 18.0},
                              {dvec3(-102.0, -10.0, -30.0), 18.0},
                              {dvec3(-88.0, -40.0, 10.0), 17.0},
                              {dvec3(-40.0, -70.0, -5.0), 15.0},
                              {dvec3(20.0, -72.0, -10.0), 15.0},
                              {dvec3(85.0, -48.0, 25.0), 15.0},
                              {dvec3(114.0, 0.0, 32.0), 15.0},
                              {dvec3(116.0, 8.0, -40.0), 14.0},
                              {dvec3(100.0, 0.0, -140.0), 14.0}}});
  scene.primitives.push_back(
      {"colon", colon, {{hu::kBowelWall, 0.0}, {hu::kLumenFluid, 3.0}}, true});
  scene.primitives.push_back(
      Solid("colon_gas",
            MakeIntersection(MakeInset(colon, 3.0),
                             MakeHalfSpace(dvec3(0.0, -55.0, 0.0), dvec3(0.0, 1.0, 0.0))),
            hu::kAir, true));
}

void AddMuscles(Scene& scene) {
  for (const double side : {1.0, -1.0}) {
    const std::string name = side > 0.0 ? "left" : "right";
    scene.primitives.push_back(Solid(name + "_psoas",
                                     MakeTube({{{dvec3(side * 27.0, 42.0, 80.0), 3.0},
                                                {dvec3(side * 33.0, 41.0, 20.0), 11.0},
                                                {dvec3(side * 43.0, 36.0, -60.0), 18.0},
                                                {dvec3(side * 55.0, 26.0, -140.0), 21.0}}}),
                                     hu::kMuscle));
    scene.primitives.push_back(Solid(name + "_quadratus_lumborum",
                                     MakeTube({{{dvec3(side * 60.0, 88.0, 70.0), 5.0},
                                                {dvec3(side * 68.0, 88.0, 10.0), 11.0},
                                                {dvec3(side * 76.0, 85.0, -60.0), 13.0},
                                                {dvec3(side * 82.0, 82.0, -140.0), 11.0}}}),
                                     hu::kMuscle));
    scene.primitives.push_back(
        Solid(name + "_erector_spinae",
              MakeEllipticPrism(dvec2(side * 38.0, 82.0), dvec2(30.0, 19.0), -1.0e4, 1.0e4, 0.0),
              hu::kMuscle));
  }
}

// --- Kidneys ----------------------------------------------------------------

constexpr dvec3 kKidneySemiAxesMm{27.5, 20.0, 55.0};  // 55 wide, 40 deep, 110 long

// side: +1 left kidney (x > 0), -1 right. The long axis tilts 15 degrees
// medially and 10 posteriorly at the upper pole; the hilum faces medially and
// 30 degrees anteriorly.
KidneyGeometry MakeKidney(const dvec3& center, double side) {
  const dvec3 along =
      glm::normalize(dvec3(-side * std::sin(15.0 * kDeg), std::sin(10.0 * kDeg), 1.0));
  const dvec3 toward = dvec3(-side * std::cos(30.0 * kDeg), -std::sin(30.0 * kDeg), 0.0);
  const dvec3 medial = glm::normalize(toward - glm::dot(toward, along) * along);
  KidneyGeometry k;
  k.center_mm = center;
  k.frame = glm::dmat3(medial, glm::cross(along, medial), along);
  k.semi_axes_mm = kKidneySemiAxesMm;
  k.artery_end_mm = center + 20.0 * medial;
  k.vein_end_mm = center + 20.0 * medial + dvec3(0.0, -6.0, 0.0);
  k.lateral_surface_mm = center - kKidneySemiAxesMm.x * medial;
  return k;
}

void AddKidney(Scene& scene, const KidneyGeometry& k, const std::string& side) {
  const dvec3 medial = k.frame[0];
  ShapePtr outline = MakeEllipsoid(k.center_mm, k.semi_axes_mm, k.frame);
  // Renal sinus: opens medially through the hilum, giving the bean shape.
  ShapePtr sinus = MakeEllipsoid(k.center_mm + 22.0 * medial, dvec3(12.0, 10.0, 30.0), k.frame);
  scene.primitives.push_back(
      Solid(side + "_kidney_cortex", MakeDifference(outline, sinus), hu::kKidneyCortex));
  scene.primitives.push_back(Solid(side + "_kidney_medulla",
                                   MakeDifference(MakeInset(outline, kKidneyCortexMm), sinus),
                                   hu::kKidneyMedulla));
  scene.primitives.push_back(Solid(
      side + "_renal_pelvis",
      MakeEllipsoid(k.center_mm + 24.0 * medial, dvec3(7.0, 6.0, 16.0), k.frame), hu::kUrine));
}

void AddUreters(Scene& scene, const AbdomenAnatomy& a) {
  for (const auto* k : {&a.left_kidney, &a.right_kidney}) {
    const double side = k->center_mm.x > 0.0 ? 1.0 : -1.0;
    const dvec3 exit = k->center_mm + 30.0 * k->frame[0] - dvec3(0.0, 0.0, 10.0);
    scene.primitives.push_back(Solid(side > 0 ? "left_ureter" : "right_ureter",
                                     MakeTube({{{k->center_mm + 24.0 * k->frame[0], 2.5},
                                                {exit, 2.5},
                                                {dvec3(side * 44.0, 12.0, -70.0), 2.5},
                                                {dvec3(side * 50.0, 4.0, -140.0), 2.5}}}),
                                     hu::kUrine));
  }
}

// --- Vessels ----------------------------------------------------------------

std::vector<TubeNode> Nodes(std::initializer_list<dvec3> points, double radius_mm) {
  std::vector<TubeNode> nodes;
  for (const dvec3& p : points) nodes.push_back({p, radius_mm});
  return nodes;
}

// Renal arteries leave the aorta at these centreline points (mm).
constexpr dvec3 kLeftRenalOrigin{14.0, 8.0, 14.0};
constexpr dvec3 kRightRenalOrigin{14.0, 8.0, 8.0};
constexpr double kAortaRadiusMm = 11.0;
constexpr double kRenalArteryRadiusMm = 3.5;
constexpr double kRenalVeinRadiusMm = 4.5;

void AddVeins(AbdomenAnatomy& a) {
  const KidneyGeometry& l = a.left_kidney;
  const KidneyGeometry& r = a.right_kidney;
  auto& v = a.vessels;
  // The left renal vein crosses in front of the aorta, behind the SMA.
  v.push_back({"left_renal_vein",
               Nodes({l.vein_end_mm, dvec3(40.0, 12.0, 11.0), dvec3(14.0, -11.5, 10.0),
                      dvec3(-22.0, 0.0, 9.0)},
                     kRenalVeinRadiusMm),
               hu::kRenalVein});
  v.push_back({"right_renal_vein",
               Nodes({r.vein_end_mm, dvec3(-36.0, 14.0, -3.0), dvec3(-24.0, 2.0, -1.0)},
                     kRenalVeinRadiusMm),
               hu::kRenalVein});
  v.push_back(
      {"portal_vein",
       Nodes({dvec3(-8.0, -22.0, 38.0), dvec3(-30.0, -15.0, 55.0), dvec3(-55.0, -8.0, 68.0)}, 7.0),
       hu::kPortalVein});
  v.push_back(
      {"splenic_vein",
       Nodes({dvec3(-8.0, -22.0, 38.0), dvec3(30.0, -8.0, 45.0), dvec3(70.0, 22.0, 66.0)}, 4.5),
       hu::kPortalVein});
  v.push_back({"ivc",
               {{dvec3(-20.0, -5.0, 200.0), 11.0},
                {dvec3(-24.0, 0.0, 60.0), 11.0},
                {dvec3(-24.0, 2.0, 0.0), 11.0},
                {dvec3(-20.0, 8.0, -70.0), 11.0},
                {dvec3(-12.0, 12.0, -95.0), 10.0}},
               hu::kIvc});
  v.push_back(
      {"iliac_veins",
       Nodes({dvec3(42.0, 20.0, -145.0), dvec3(25.0, 18.0, -110.0), dvec3(-12.0, 12.0, -95.0),
              dvec3(-28.0, 16.0, -120.0), dvec3(-36.0, 18.0, -145.0)},
             7.0),
       hu::kIvc});
}

void AddArteries(AbdomenAnatomy& a) {
  auto& v = a.vessels;
  v.push_back({"left_renal_artery",
               Nodes({kLeftRenalOrigin, dvec3(38.0, 22.0, 12.0), a.left_kidney.artery_end_mm},
                     kRenalArteryRadiusMm),
               hu::kArtery});
  // The right renal artery runs behind the IVC, in front of spine and psoas.
  v.push_back({"right_renal_artery",
               Nodes({kRightRenalOrigin, dvec3(-4.0, 18.0, 6.0), dvec3(-26.0, 19.0, 2.0),
                      a.right_kidney.artery_end_mm},
                     kRenalArteryRadiusMm),
               hu::kArtery});
  v.push_back({"superior_mesenteric_artery",
               Nodes({dvec3(14.0, -3.0, 32.0), dvec3(14.0, -22.0, 22.0), dvec3(15.0, -35.0, 0.0),
                      dvec3(18.0, -48.0, -60.0), dvec3(20.0, -55.0, -140.0)},
                     3.5),
               hu::kArtery});
  v.push_back({"celiac_trunk", Nodes({dvec3(12.0, -3.0, 50.0), dvec3(12.0, -18.0, 56.0)}, 3.5),
               hu::kArtery});
  v.push_back({"splenic_artery",
               Nodes({dvec3(12.0, -18.0, 56.0), dvec3(40.0, -12.0, 64.0), dvec3(60.0, 5.0, 72.0),
                      dvec3(78.0, 25.0, 76.0)},
                     2.5),
               hu::kArtery});
  v.push_back(
      {"hepatic_artery",
       Nodes({dvec3(12.0, -18.0, 56.0), dvec3(-15.0, -26.0, 60.0), dvec3(-45.0, -18.0, 70.0)}, 2.5),
       hu::kArtery});
  v.push_back({"iliac_arteries",
               Nodes({dvec3(48.0, 10.0, -145.0), dvec3(30.0, 5.0, -100.0), dvec3(13.0, 3.0, -75.0),
                      dvec3(-8.0, 6.0, -100.0), dvec3(-30.0, 12.0, -145.0)},
                     7.0),
               hu::kArtery});
  v.push_back({"aorta",
               {{dvec3(8.0, 6.0, 200.0), kAortaRadiusMm},
                {dvec3(12.0, 7.0, 60.0), kAortaRadiusMm},
                {kLeftRenalOrigin, kAortaRadiusMm},
                {dvec3(14.0, 5.0, -40.0), 10.0},
                {dvec3(13.0, 3.0, -75.0), 9.0}},
               hu::kAorta});
}

// The centreline point halfway between where a branch leaves the aorta
// (its first node, on the aorta's centreline) and its end.
dvec3 MidwayFromAortaWall(const Vessel& branch) {
  std::vector<dvec3> points;
  for (const TubeNode& node : branch.centreline) points.push_back(node.point_mm);
  return PointAtArcLength(points, 0.5 * (kAortaRadiusMm + PolylineLength(points)));
}

}  // namespace

const Vessel* AbdomenAnatomy::FindVessel(std::string_view name) const {
  for (const Vessel& v : vessels) {
    if (v.name == name) return &v;
  }
  return nullptr;
}

AbdomenAnatomy MakeAbdomenAnatomy() {
  AbdomenAnatomy a;
  // The right kidney sits lower, under the liver.
  a.left_kidney = MakeKidney(dvec3(78.0, 54.0, 10.0), 1.0);
  a.right_kidney = MakeKidney(dvec3(-76.0, 56.0, -6.0), -1.0);
  a.vertebral_body_mm = dvec3(0.0, 40.0, 0.0);
  a.aorta_at_renal_mm = kLeftRenalOrigin;
  a.liver_mm = dvec3(-85.0, 0.0, 75.0);
  a.spleen_mm = dvec3(92.0, 45.0, 88.0);
  // Painting order: veins, then arteries over them, the aorta last.
  AddVeins(a);
  AddArteries(a);
  a.left_renal_artery_mm = MidwayFromAortaWall(*a.FindVessel("left_renal_artery"));
  a.right_renal_artery_mm = MidwayFromAortaWall(*a.FindVessel("right_renal_artery"));
  return a;
}

Scene MakeAbdomenScene(const AbdomenAnatomy& anatomy) {
  Scene scene;
  scene.cross_section = BodyCrossSection;
  scene.bowel = BowelTexture();
  AddSolidOrgans(scene, anatomy);
  for (const auto& [kidney, side] :
       {std::pair{&anatomy.left_kidney, "left"}, std::pair{&anatomy.right_kidney, "right"}}) {
    scene.primitives.push_back(Solid(std::string(side) + "_perirenal_fat",
                                     MakeEllipsoid(kidney->center_mm + 3.0 * kidney->frame[0],
                                                   kidney->semi_axes_mm + 14.0, kidney->frame),
                                     hu::kFat));
  }
  AddMuscles(scene);
  AddKidney(scene, anatomy.left_kidney, "left");
  AddKidney(scene, anatomy.right_kidney, "right");
  AddUreters(scene, anatomy);
  for (const Vessel& v : anatomy.vessels) {
    scene.primitives.push_back(Solid(v.name, MakeTube({v.centreline}), v.hu));
  }
  AddAbdomenSkeleton(scene);
  return scene;
}

}  // namespace vpm::phantom
