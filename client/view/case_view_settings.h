// A case's kept view (CaseInfo.view, docs/CASES.md) over the viewer's own
// settings, as vpm-view opens a case: what the frame shows is the case's
// (mode, preset, render_tf, mip_window, crop, clip, view_cut, slices; world
// LPS, mm), how it comes is the viewer's (width, height, overlay, encoding,
// jpeg_quality, interactive_quality).
#pragma once

#include "client/view/crop_box_drag.h"
#include "vpm/v3/vpm.pb.h"

namespace vpm::view {

v3::RenderSettings WithCaseView(const v3::RenderSettings& own, const v3::RenderSettings& view);

// A stored crop box as the viewer's (world mm).
WorldBox CropBoxFromProto(const v3::CropBox& crop);

}  // namespace vpm::view
