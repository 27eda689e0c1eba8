#include "server/raycast/slicer_presets.h"

namespace vpm {
namespace {

using glm::dvec3;

// Slicer's CT presets share one lighting (shaded, ambient 0.1, diffuse 0.9,
// specular 0.2, power 10) and one colour ramp: black, brown-red, orange,
// near white, lilac at 3071 HU.
constexpr TfLighting kCtLighting{true, 0.1, 0.9, 0.2, 10.0};

RenderTransferFunction SlicerCtAaa() {
  return {"CT-AAA",
          {{-3024, dvec3(0, 0, 0)},
           {143.556, dvec3(0.615686, 0.356863, 0.184314)},
           {166.222, dvec3(0.882353, 0.603922, 0.290196)},
           {214.389, dvec3(1, 1, 1)},
           {419.736, dvec3(1, 0.937033, 0.954531)},
           {3071, dvec3(0.827451, 0.658824, 1)}},
          {{-3024, 0}, {143.556, 0}, {166.222, 0.686275}, {214.389, 0.696078},
           {419.736, 0.833333}, {3071, 0.803922}},
          kCtLighting};
}

RenderTransferFunction SlicerCtBone() {
  return {"CT-Bone",
          {{-3024, dvec3(0, 0, 0)},
           {-16.4458, dvec3(0.729412, 0.254902, 0.301961)},
           {641.385, dvec3(0.905882, 0.815686, 0.552941)},
           {3071, dvec3(1, 1, 1)}},
          {{-3024, 0}, {-16.4458, 0}, {641.385, 0.715686}, {3071, 0.705882}},
          kCtLighting};
}

RenderTransferFunction SlicerCtMuscle() {
  return {"CT-Muscle",
          {{-3024, dvec3(0, 0, 0)},
           {-155.407, dvec3(0.54902, 0.25098, 0.14902)},
           {217.641, dvec3(0.882353, 0.603922, 0.290196)},
           {419.736, dvec3(1, 0.937033, 0.954531)},
           {3071, dvec3(0.827451, 0.658824, 1)}},
          {{-3024, 0}, {-155.407, 0}, {217.641, 0.676471}, {419.736, 0.833333}, {3071, 0.803922}},
          kCtLighting};
}

RenderTransferFunction SlicerCtChestContrastEnhanced() {
  return {"CT-Chest-Contrast-Enhanced",
          {{-3024, dvec3(0, 0, 0)},
           {67.0106, dvec3(0.54902, 0.25098, 0.14902)},
           {251.105, dvec3(0.882353, 0.603922, 0.290196)},
           {439.291, dvec3(1, 0.937033, 0.954531)},
           {3071, dvec3(0.827451, 0.658824, 1)}},
          {{-3024, 0}, {67.0106, 0}, {251.105, 0.446429}, {439.291, 0.625}, {3071, 0.616071}},
          kCtLighting};
}

// Slicer's soft tissue is a grey, unshaded, opaque surface from -160 HU
// (fat and everything denser), white from 240 HU.
RenderTransferFunction SlicerCtSoftTissue() {
  return {"CT-Soft-Tissue",
          {{-2048, dvec3(0, 0, 0)},
           {-167.01, dvec3(0, 0, 0)},
           {-160, dvec3(0.0556356)},
           {240, dvec3(1, 1, 1)},
           {3661, dvec3(1, 1, 1)}},
          {{-2048, 0}, {-167.01, 0}, {-160, 1}, {240, 1}, {3661, 1}},
          TfLighting{false, 0.2, 1.0, 0.0, 1.0}};
}

RenderTransferFunction SlicerMrDefault() {
  return {"MR-Default",
          {{0, dvec3(0, 0, 0)},
           {20, dvec3(0.168627, 0, 0)},
           {40, dvec3(0.403922, 0.145098, 0.0784314)},
           {120, dvec3(0.780392, 0.607843, 0.380392)},
           {220, dvec3(0.847059, 0.835294, 0.788235)},
           {1024, dvec3(1, 1, 1)}},
          {{0, 0}, {20, 0}, {40, 0.15}, {120, 0.3}, {220, 0.375}, {1024, 0.5}},
          TfLighting{true, 0.2, 1.0, 0.0, 1.0}};
}

}  // namespace

std::vector<std::pair<std::string, std::string>> SlicerPresetNames() {
  return {
      {"CT-AAA", "Slicer: abdominal aortic aneurysm, contrast vessels and bone from 144 HU"},
      {"CT-Bone", "Slicer: bone white, soft tissue faint red (opacity from -16 HU)"},
      {"CT-Muscle", "Slicer: muscle red-brown, bone white (opacity from -155 HU)"},
      {"CT-Chest-Contrast-Enhanced", "Slicer: contrast chest, vessels and bone from 67 HU"},
      {"CT-Soft-Tissue", "Slicer: opaque grey skin surface from -160 HU, unshaded"},
      {"MR-Default", "Slicer: MRI, 0..1024, dark red to white"},
  };
}

std::optional<RenderTransferFunction> SlicerPreset(std::string_view name) {
  if (name == "CT-AAA") return SlicerCtAaa();
  if (name == "CT-Bone") return SlicerCtBone();
  if (name == "CT-Muscle") return SlicerCtMuscle();
  if (name == "CT-Chest-Contrast-Enhanced") return SlicerCtChestContrastEnhanced();
  if (name == "CT-Soft-Tissue") return SlicerCtSoftTissue();
  if (name == "MR-Default") return SlicerMrDefault();
  return std::nullopt;
}

}  // namespace vpm
