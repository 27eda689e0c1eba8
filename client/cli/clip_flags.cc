#include "client/cli/clip_flags.h"

#include "proto/vec3_convert.h"

namespace vpm::cli {

void AddClipFlags(CLI::App* app, ClipFlags* flags) {
  app->add_option("--crop", flags->crop,
                  "show only the box X0 Y0 Z0 X1 Y1 Z1 (world LPS mm, as `vpm volume info` "
                  "prints the volume's box)")
      ->expected(6);
  app->add_option("--clip", flags->clip,
                  "clip plane NX NY NZ D: keeps the side dot(n, x) >= D (world LPS mm); "
                  "repeatable")
      ->expected(4);
  app->add_option("--cut", flags->cut,
                  "cut away what lies in front of the grabbed tissue (with no grab: the "
                  "orbit centre), facing the camera: auto (on unless --crop or --clip), on, off")
      ->check(CLI::IsMember({"auto", "on", "off"}))
      ->capture_default_str();
}

Result<ClipChoice> ToClipChoice(const ClipFlags& flags) {
  ClipChoice choice;
  if (!flags.crop.empty()) {
    if (flags.crop.size() != 6) return absl::InvalidArgumentError("--crop takes 6 numbers");
    choice.region.crop = CropBox{glm::dvec3(flags.crop[0], flags.crop[1], flags.crop[2]),
                                 glm::dvec3(flags.crop[3], flags.crop[4], flags.crop[5])};
  }
  for (const std::vector<double>& c : flags.clip) {
    if (c.size() != 4) return absl::InvalidArgumentError("--clip takes 4 numbers: NX NY NZ D");
    choice.region.planes.push_back(ClipPlane{glm::dvec3(c[0], c[1], c[2]), c[3]});
  }
  if (Status valid = ValidateClipRegion(choice.region); !valid.ok()) {
    return absl::InvalidArgumentError(StrCat("--crop/--clip: ", valid.message()));
  }
  choice.view_cut = flags.cut == "on" || (flags.cut == "auto" && choice.region.empty());
  return choice;
}

void FillClipSettings(const ClipChoice& choice, v3::RenderSettings* settings) {
  if (choice.region.crop) {
    *settings->mutable_crop()->mutable_lo_mm() = ToProto(choice.region.crop->lo_mm);
    *settings->mutable_crop()->mutable_hi_mm() = ToProto(choice.region.crop->hi_mm);
  }
  for (const ClipPlane& plane : choice.region.planes) {
    v3::ClipPlane* out = settings->add_clip();
    *out->mutable_normal() = ToProto(plane.normal);
    out->set_offset_mm(plane.offset_mm);
  }
  settings->set_view_cut(choice.view_cut);
}

}  // namespace vpm::cli
