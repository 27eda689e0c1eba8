#include "server/service/case_view.h"

namespace vpm::service {

v3::RenderSettings CaseView(const v3::RenderSettings& settings) {
  v3::RenderSettings view = settings;
  view.clear_width();
  view.clear_height();
  view.clear_overlay();
  view.clear_encoding();
  view.clear_jpeg_quality();
  view.clear_interactive_quality();
  return view;
}

Result<v3::RenderSettings> ParseCaseView(const std::string& bytes, std::string_view case_id) {
  v3::RenderSettings view;
  if (bytes.size() > kMaxCaseViewBytes || !view.ParseFromString(bytes)) {
    return absl::DataLossError(
        StrCat("case '", case_id, "': its stored render settings are unreadable"));
  }
  return view;
}

Status CheckCaseViewSize(const v3::RenderSettings& view, std::string_view field) {
  const size_t bytes = view.ByteSizeLong();
  if (bytes <= kMaxCaseViewBytes) return absl::OkStatus();
  return absl::InvalidArgumentError(
      StrCat(field, ": ", bytes, " bytes; at most ", kMaxCaseViewBytes));
}

}  // namespace vpm::service
