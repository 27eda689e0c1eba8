// The view a case keeps (CaseInfo.view, docs/CASES.md): the render settings
// a client of its session last set, less what is each client's own: the
// frame's size (width, height), its encoding (encoding, jpeg_quality), the
// proxy-mesh overlay and the interactive quality. What stays: mode, preset, render_tf, mip_window,
// crop, clip, view_cut, slices (world LPS, mm, as sent).
#pragma once

#include <cstddef>
#include <string>
#include <string_view>

#include "server/common/status.h"
#include "vpm/v3/vpm.pb.h"

namespace vpm::service {

// Serialized bytes. A valid RenderSettings is far below this: a render_tf
// of 2 x 1024 points (kMaxRenderTfPoints) is about 90 KiB, 16 planes and 3
// slices under 2 KiB.
inline constexpr size_t kMaxCaseViewBytes = 256 * 1024;

// `settings` without the per-client fields.
v3::RenderSettings CaseView(const v3::RenderSettings& settings);

// A view as stored (CaseRecord::render_settings; empty: none): the
// message, or DataLoss naming the case when the bytes do not parse or are
// over kMaxCaseViewBytes.
Result<v3::RenderSettings> ParseCaseView(const std::string& bytes, std::string_view case_id);

// InvalidArgument naming `field` ("archive.view: ...") when `view` is over
// kMaxCaseViewBytes; its values are checked where it is used, as a stream's
// settings (ToStreamSettings).
Status CheckCaseViewSize(const v3::RenderSettings& view, std::string_view field);

}  // namespace vpm::service
