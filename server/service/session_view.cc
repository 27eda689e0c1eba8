// A session's view (docs/CASES.md): the owner's last render settings, kept
// on the event path without a write and stored in the case with the next
// still frame, so that the case reopens with its preset, crop, clips and
// slices, and a frame nobody asked for (the export's capture) shows them.
#include <algorithm>
#include <cstdio>

#include "server/service/case_view.h"
#include "server/service/session.h"

namespace vpm::service {

void Session::KeepView(const v3::RenderSettings& settings) {
  v3::RenderSettings view = CaseView(settings);
  std::string bytes = view.SerializeAsString();
  if (bytes.size() > kMaxCaseViewBytes) {
    std::fprintf(stderr,
                 "vpm-server: session %s: render settings of %zu bytes not kept (at most %zu)\n",
                 id_.c_str(), bytes.size(), kMaxCaseViewBytes);
    return;
  }
  std::lock_guard lock(view_mutex_);
  if (kept_view_ && bytes == kept_view_bytes_) return;
  kept_view_ = std::move(view);
  kept_view_bytes_ = std::move(bytes);
}

std::optional<v3::RenderSettings> Session::kept_view() const {
  std::lock_guard lock(view_mutex_);
  return kept_view_;
}

void Session::StoreViewInCase() {
  if (case_store_ == nullptr) return;
  // One write at a time, so that an older view never lands after a newer.
  std::lock_guard store_lock(view_store_mutex_);
  std::string bytes;
  {
    std::lock_guard lock(view_mutex_);
    if (!kept_view_ || kept_view_bytes_ == stored_view_bytes_) return;
    bytes = kept_view_bytes_;
  }
  // The view is part of the case, but a view the store cannot keep is no
  // reason to refuse a frame: it is said, and tried again with the next
  // still.
  if (Status stored = case_store_->SetRenderSettings(case_id_, bytes); !stored.ok()) {
    std::fprintf(stderr, "vpm-server: session %s: render settings not stored: %s\n", id_.c_str(),
                 stored.ToString().c_str());
    return;
  }
  std::lock_guard lock(view_mutex_);
  stored_view_bytes_ = std::move(bytes);
}

Result<SceneView> Session::ExportView(const SceneView& last) const {
  const bool rendered = !last.preset.points.empty();
  std::optional<v3::RenderSettings> kept = kept_view();
  if (rendered && !kept) return last;
  v3::RenderSettings settings = kept ? *kept : v3::RenderSettings();
  if (rendered) {
    settings.set_width(last.width);
    settings.set_height(last.height);
  }
  // No frame yet: the defaults a stream starts with (512 x 512).
  const int max_side = std::max({1024, last.width, last.height});
  ASSIGN_OR_RETURN(const StreamSettings chosen,
                   ToStreamSettings(settings, volume_->volume, max_side));
  SceneView view = chosen.view;
  view.camera = last.camera;
  return view;
}

}  // namespace vpm::service
