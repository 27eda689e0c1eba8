#include "client/view/viewer_app.h"

#include <cmath>
#include <cstdio>
#include <ctime>
#include <filesystem>
#include <fstream>

#include "client/view/case_view_settings.h"
#include "client/view/slice_panes.h"
#include "client/view/status_text.h"
#include "proto/enum_names.h"

namespace vpm::view {
namespace {

constexpr auto kNoticeTime = std::chrono::milliseconds(2500);
constexpr auto kResizeQuiet = std::chrono::milliseconds(200);  // debounce of window resizes

// Key I: auto -> fast -> balanced -> sharp -> auto.
v3::InteractiveQuality NextInteractiveQuality(v3::InteractiveQuality q) {
  switch (q) {
    case v3::INTERACTIVE_QUALITY_FAST:
      return v3::INTERACTIVE_QUALITY_BALANCED;
    case v3::INTERACTIVE_QUALITY_BALANCED: return v3::INTERACTIVE_QUALITY_SHARP;
    case v3::INTERACTIVE_QUALITY_SHARP:
      return v3::INTERACTIVE_QUALITY_UNSPECIFIED;
    default:
      return v3::INTERACTIVE_QUALITY_FAST;
  }
}

// The transfer function an action picks (DVR), null for other actions.
const char* PresetOfAction(Action action) {
  switch (action) {
    case Action::kPresetSoftTissue:
      return "ct-soft-tissue";
    case Action::kPresetBone:
      return "ct-bone";
    case Action::kPresetVessels:
      return "ct-vessels";
    case Action::kPresetMriT1:
      return "mri-t1";
    case Action::kPresetSlicerAaa:
      return "CT-AAA";
    case Action::kPresetSlicerBone:
      return "CT-Bone";
    case Action::kPresetSlicerMuscle:
      return "CT-Muscle";
    case Action::kPresetSlicerChest:
      return "CT-Chest-Contrast-Enhanced";
    case Action::kPresetSlicerSoftTissue:
      return "CT-Soft-Tissue";
    case Action::kPresetSlicerMr:
      return "MR-Default";
    default:
      return nullptr;
  }
}

}  // namespace

ViewerApp::ViewerApp(ViewFlags flags) : flags_(std::move(flags)) {
  settings_.set_mode(RenderModeFromName(flags_.mode).value_or(v3::RENDER_MODE_DVR));
  settings_.set_preset(flags_.preset);
  settings_.set_width(flags_.width);
  settings_.set_height(flags_.height);
  settings_.set_overlay(flags_.overlay);
  settings_.set_interactive_quality(InteractiveQualityFromName(flags_.interactive_quality)
                                        .value_or(v3::INTERACTIVE_QUALITY_UNSPECIFIED));
  view_cut_ = flags_.view_cut;
  settings_.set_encoding(v3::ENCODING_JPEG);
  settings_.set_jpeg_quality(flags_.jpeg_quality);
}

ViewerApp::~ViewerApp() {
  if (connection_) connection_->Stop();
  window_.reset();
  SDL_Quit();
}

int ViewerApp::Run() {
  if (SDL_Init(SDL_INIT_VIDEO) != 0) {
    std::fprintf(stderr, "vpm-view: SDL: %s (is DISPLAY set?)\n", SDL_GetError());
    return 1;
  }
  auto window = ViewerWindow::Create("vpm-view " + flags_.connection.server.address,
                                     flags_.width, flags_.height);
  if (!window.ok()) {
    std::fprintf(stderr, "vpm-view: %s\n", std::string(window.status().message()).c_str());
    return 1;
  }
  window_ = std::move(*window);
  wake_event_ = SDL_RegisterEvents(1);
  connection_ = std::make_unique<InteractConnection>(flags_.connection, [this] {
    if (wake_pending_.exchange(true)) return;
    SDL_Event e{};
    e.type = wake_event_;
    SDL_PushEvent(&e);
  });
  SendSettings();
  connection_->Start();
  while (running_) {
    SDL_Event event;
    if (SDL_WaitEventTimeout(&event, 50)) {
      HandleEvent(event);
      while (running_ && SDL_PollEvent(&event)) HandleEvent(event);
    }
    PollConnection();
    if (resize_at_ && SteadyClock::now() >= *resize_at_) {
      resize_at_.reset();
      const SDL_Rect area = window_->FrameArea();
      settings_.set_width(std::clamp(area.w, 16, 4096));
      settings_.set_height(std::clamp(area.h, 16, 4096));
      SendSettings();
    }
    Paint();
  }
  return 0;
}

void ViewerApp::HandleEvent(const SDL_Event& e) {
  if (e.type == wake_event_) {
    wake_pending_ = false;
    return;
  }
  if (e.type == SDL_KEYDOWN || e.type == SDL_KEYUP) event_mod_ = SDL_Keymod(e.key.keysym.mod);
  switch (e.type) {
    case SDL_QUIT:
      running_ = false;
      break;
    case SDL_WINDOWEVENT:
      if (e.window.event == SDL_WINDOWEVENT_SIZE_CHANGED) {
        resize_at_ = SteadyClock::now() + kResizeQuiet;
      }
      // Keys may have gone up or down while another window had the focus.
      if (e.window.event == SDL_WINDOWEVENT_FOCUS_GAINED) event_mod_ = SDL_GetModState();
      break;
    case SDL_KEYDOWN: {
      if (show_cases_) {  // the panel takes the keys while it shows
        OnCasePanelKey(SDL_GetKeyName(e.key.keysym.sym));
        break;
      }
      const std::string key = KeyNameWithModifiers(SDL_GetKeyName(e.key.keysym.sym),
                                                   (event_mod_ & (KMOD_CTRL | KMOD_GUI)) != 0,
                                                   ShiftHeld());
      if (auto action = ActionForKey(key)) OnAction(*action);
      break;
    }
    case SDL_TEXTINPUT:
      if (show_cases_ && case_panel_.renaming()) {
        if (skip_text_) {
          skip_text_ = false;
        } else {
          case_panel_.OnText(e.text.text);
        }
      }
      break;
    case SDL_MOUSEBUTTONDOWN:
      OnButtonDown(e.button);
      break;
    case SDL_MOUSEBUTTONUP:
      OnButtonUp(e.button);
      break;
    case SDL_MOUSEMOTION:
      OnMotion(e.motion);
      break;
    case SDL_MOUSEWHEEL:
      if (camera_ && e.wheel.y != 0) {
        const int clicks = e.wheel.direction == SDL_MOUSEWHEEL_FLIPPED ? -e.wheel.y : e.wheel.y;
        const double step = ShiftHeld() ? 5.0 : 1.0;
        if (ScrollSliceAt(last_x_, last_y_, clicks * step)) break;
        camera_->Zoom(clicks);
        SendCamera();
      }
      break;
    default:
      break;
  }
}

void ViewerApp::OnAction(Action action) {
  if (const char* preset = PresetOfAction(action)) {
    settings_.set_mode(v3::RENDER_MODE_DVR);
    settings_.set_preset(preset);
    SendSettings();
    Notice(StrCat("DVR ", preset));
    return;
  }
  if (OnSettingsAction(action)) return;
  switch (action) {
    case Action::kToggleHelp: show_help_ = !show_help_; break;
    case Action::kToggleCases: ToggleCases(); break;
    case Action::kToggleGrabMode:
      grab_mode_ = !grab_mode_;
      Notice(grab_mode_ ? "grab mode: left drag pulls tissue" : "grab mode off: left drag orbits");
      break;
    case Action::kToggleSlices:
      ToggleSlices();
      break;
    case Action::kToggleCropMode:
      ToggleCropMode();
      break;
    case Action::kToggleClipPlane:
      ToggleClipPlane();
      break;
    case Action::kAddClipPlane:
      AddClipPlane();
      break;
    case Action::kScrollForward:
      ScrollByKey(1.0);
      break;
    case Action::kScrollBack:
      ScrollByKey(-1.0);
      break;
    case Action::kRefineHere:
      RefineAtCursor();
      break;
    case Action::kResetView:
      if (camera_) camera_->Reset(), SendCamera();
      break;
    case Action::kResetDeformation:
      ResetDeformation();
      break;
    case Action::kPinHere:
      PinAtCursor();
      break;
    case Action::kUndo:
      connection_->Undo(false);
      break;
    case Action::kRedo:
      connection_->Undo(true);
      break;
    case Action::kScreenshot:
      SaveScreenshot();
      break;
    case Action::kQuit:
      running_ = false;
      break;
    default:
      break;
  }
}

bool ViewerApp::OnSettingsAction(Action action) {
  switch (action) {
    case Action::kToggleViewCut:
      view_cut_ = !view_cut_;
      SendSettings();
      Notice(view_cut_ ? "view cut on (while no crop or clip)" : "view cut off");
      return true;
    case Action::kCycleInteractiveQuality:
      settings_.set_interactive_quality(NextInteractiveQuality(settings_.interactive_quality()));
      SendSettings();
      Notice(StrCat("frames while moving: ",
                    InteractiveQualityName(settings_.interactive_quality())));
      return true;
    case Action::kMip:
      settings_.set_mode(settings_.mode() == v3::RENDER_MODE_MIP ? v3::RENDER_MODE_DVR
                                                                 : v3::RENDER_MODE_MIP);
      SendSettings();
      Notice(settings_.mode() == v3::RENDER_MODE_MIP ? "MIP" : "DVR");
      return true;
    case Action::kToggleOverlay:
      settings_.set_overlay(!settings_.overlay());
      SendSettings();
      return true;
    default:
      return false;
  }
}

void ViewerApp::ScrollByKey(double sign) {
  const double step = ShiftHeld() ? 5.0 : 1.0;
  int x = 0, y = 0;
  SDL_GetMouseState(&x, &y);
  if (!ScrollSliceAt(x, y, sign * step) && settings_.clip_size() > 0) {
    MoveClipPlane(sign * step);
  }
}

void ViewerApp::ResetDeformation() {
  v3::ClientEvent event;
  event.mutable_reset();
  connection_->Send(event);
  grabbed_ = false;
  gesture_ = Gesture::kNone;
  Notice("back to rest: kept drags and pins dropped");
}

void ViewerApp::OnButtonDown(const SDL_MouseButtonEvent& b) {
  last_x_ = b.x;
  last_y_ = b.y;
  if (gesture_ != Gesture::kNone) return;
  if (b.button == SDL_BUTTON_LEFT) {
    if (const std::optional<SlicePixel> on_slice = window_->ToSlicePixel(b.x, b.y)) {
      // Slices are driven by the wheel and, in grab mode, by a pull.
      if (grab_mode_) StartSlicePull(*on_slice);
      return;
    }
    if (grab_mode_) return StartPull(b.x, b.y);
    if (ShiftHeld() && settings_.clip_size() > 0) {
      gesture_ = Gesture::kClipPlane;
      drag_clip_start_ = settings_.clip(settings_.clip_size() - 1);
      pull_from_x_ = b.x, pull_from_y_ = b.y;
      return;
    }
    if (const std::optional<BoxFace> face = FaceAt(b.x, b.y)) {
      gesture_ = Gesture::kCropFace;
      drag_face_ = *face;
      drag_box_start_ = crop_box_;
      pull_from_x_ = b.x, pull_from_y_ = b.y;
      return;
    }
    gesture_ = Gesture::kOrbit;
  } else if (b.button == SDL_BUTTON_MIDDLE || b.button == SDL_BUTTON_RIGHT) {
    gesture_ = Gesture::kPan;
  }
}

void ViewerApp::OnButtonUp(const SDL_MouseButtonEvent& b) {
  const bool ends = (gesture_ == Gesture::kPan)
                        ? (b.button == SDL_BUTTON_MIDDLE || b.button == SDL_BUTTON_RIGHT)
                        : b.button == SDL_BUTTON_LEFT;
  if (!ends) return;
  if (gesture_ == Gesture::kPull || gesture_ == Gesture::kSlicePull) {
    const bool keep = ShiftHeld();
    LetGo(keep);
    if (keep) Notice("drag kept: X returns to rest");
  }
  gesture_ = Gesture::kNone;
}

void ViewerApp::OnMotion(const SDL_MouseMotionEvent& m) {
  const double dx = m.x - last_x_, dy = m.y - last_y_;
  last_x_ = m.x;
  last_y_ = m.y;
  if (gesture_ == Gesture::kNone && crop_mode_) hover_face_ = FaceAt(m.x, m.y);
  if (!camera_ || gesture_ == Gesture::kNone) return;
  const double scale = FramePixelsPerWindowPixel();
  const int fw = settings_.width(), fh = settings_.height();
  const double from_dx = (m.x - pull_from_x_) * scale, from_dy = (m.y - pull_from_y_) * scale;
  if (gesture_ == Gesture::kSlicePull && grabbed_) {
    const glm::dvec3 offset =
        SliceDragOffsetMm(pull_slice_, (m.x - pull_from_x_) * pull_slice_scale_,
                          (m.y - pull_from_y_) * pull_slice_scale_);
    v3::ClientEvent event;
    event.mutable_drag()->mutable_offset_mm()->set_x(offset.x);
    event.mutable_drag()->mutable_offset_mm()->set_y(offset.y);
    event.mutable_drag()->mutable_offset_mm()->set_z(offset.z);
    connection_->Send(event);
    return;
  }
  if (gesture_ == Gesture::kCropFace && geometry_) {
    const double delta = FaceDragMm(*camera_, *geometry_, drag_face_, from_dx, from_dy,
                                    window_->frame_width(), window_->frame_height());
    crop_box_ = MoveBoxFace(drag_box_start_, drag_face_, delta, VolumeWorldBox(*geometry_));
    *settings_.mutable_crop() = CropBoxToProto(crop_box_);
    SendSettings();
    return;
  }
  if (gesture_ == Gesture::kClipPlane && geometry_) {
    const double delta = ClipDragMm(*camera_, *geometry_, drag_clip_start_, from_dx, from_dy,
                                    window_->frame_width(), window_->frame_height());
    *settings_.mutable_clip(settings_.clip_size() - 1) =
        vpm::view::MoveClipPlane(drag_clip_start_, delta, VolumeWorldBox(*geometry_));
    SendSettings();
    return;
  }
  if (gesture_ == Gesture::kOrbit) {
    camera_->Orbit(dx, dy);
    SendCamera();
  } else if (gesture_ == Gesture::kPan) {
    camera_->Pan(dx * scale, dy * scale, fw, fh);
    SendCamera();
  } else if (gesture_ == Gesture::kPull && grabbed_ && geometry_) {
    // The camera works in physical voxel space; the API takes world LPS.
    const glm::dvec3 offset = geometry_->PhysicalVectorToWorld(camera_->DragOffsetMm(
        (m.x - pull_from_x_) * scale, (m.y - pull_from_y_) * scale, fw, fh));
    v3::ClientEvent event;
    event.mutable_drag()->mutable_offset_mm()->set_x(offset.x);
    event.mutable_drag()->mutable_offset_mm()->set_y(offset.y);
    event.mutable_drag()->mutable_offset_mm()->set_z(offset.z);
    connection_->Send(event);
  }
}

void ViewerApp::StartPull(int window_x, int window_y) {
  if (!camera_) return;
  if (grabbed_) LetGo();  // a grab still held ends when a new one starts
  const std::optional<SDL_Point> px = window_->ToFramePixel(window_x, window_y);
  if (!px || !camera_->PickPoint(px->x, px->y, window_->frame_width(), window_->frame_height())) {
    Notice("nothing to grab there: the point is outside the volume");
    return;
  }
  v3::ClientEvent event;
  v3::Grab* grab = event.mutable_grab();
  grab->set_pick(true);
  grab->set_pixel_x(px->x);
  grab->set_pixel_y(px->y);
  connection_->Send(event);
  grabbed_ = true;
  gesture_ = Gesture::kPull;
  pull_from_x_ = window_x;
  pull_from_y_ = window_y;
}

void ViewerApp::LetGo(bool keep) {
  v3::ClientEvent event;
  event.mutable_release()->set_keep(keep);
  connection_->Send(event);
  grabbed_ = false;
}

void ViewerApp::PinAtCursor() {
  int x = 0, y = 0;
  SDL_GetMouseState(&x, &y);
  const std::optional<SDL_Point> px = window_->ToFramePixel(x, y);
  if (!camera_ || !px ||
      !camera_->PickPoint(px->x, px->y, window_->frame_width(), window_->frame_height())) {
    return Notice("pin: put the cursor over the volume");
  }
  v3::ClientEvent event;
  v3::Pin* pin = event.mutable_pin();
  pin->set_pick(true);
  pin->set_pixel_x(px->x);
  pin->set_pixel_y(px->y);
  connection_->Send(event);
  Notice("pinned: the tissue under the cursor holds still");
}

void ViewerApp::RefineAtCursor() {
  int x = 0, y = 0;
  SDL_GetMouseState(&x, &y);
  const std::optional<SDL_Point> px = window_->ToFramePixel(x, y);
  const std::optional<glm::dvec3> point =
      (camera_ && px) ? camera_->PickPoint(px->x, px->y, window_->frame_width(),
                                           window_->frame_height())
                      : std::nullopt;
  if (!point || !geometry_) return Notice("refine: put the cursor over the volume");
  grabbed_ = false;
  gesture_ = Gesture::kNone;
  connection_->RefineAt(geometry_->PhysicalToWorld(*point));  // RefineMesh takes world LPS
  Notice("refining the mesh at the cursor ...");
}

void ViewerApp::SaveScreenshot() {
  Paint();
  auto pixels = window_->ReadPixels();
  Result<std::vector<uint8_t>> png =
      pixels.ok() ? EncodePng(pixels->rgba, pixels->width, pixels->height) : pixels.status();
  if (!png.ok()) return Notice(StrCat("screenshot failed: ", png.status().message()));
  char stamp[32];
  const std::time_t now = std::time(nullptr);
  std::strftime(stamp, sizeof stamp, "%Y%m%d-%H%M%S", std::localtime(&now));
  const std::filesystem::path path = std::filesystem::path(flags_.screenshot_dir) /
                                     StrCat("vpm-view-", stamp, "-", ++screenshots_, ".png");
  std::ofstream file(path, std::ios::binary);
  file.write(reinterpret_cast<const char*>(png->data()), std::streamsize(png->size()));
  if (!file) return Notice(StrCat("screenshot: cannot write ", path.string()));
  std::printf("screenshot %s\n", path.c_str());
  std::fflush(stdout);
  Notice(StrCat("saved ", path.string()));
}

void ViewerApp::PollConnection() {
  const ConnectionState state = connection_->state();
  if (state.stream_generation != stream_generation_) {
    // A new stream: the server holds no grab of ours any more.
    stream_generation_ = state.stream_generation;
    grabbed_ = false;
    if (gesture_ == Gesture::kPull || gesture_ == Gesture::kSlicePull) gesture_ = Gesture::kNone;
  }
  if (state.volume && state.volume->volume_id() != volume_id_) {
    volume_id_ = state.volume->volume_id();
    auto geometry = GeometryFromProto(*state.volume);
    if (!geometry.ok()) {
      Notice(std::string(geometry.status().message()));
    } else if (!camera_) {
      // A restarted server gives the same volume a new id: the view stays.
      camera_.emplace(*geometry);
      geometry_ = *geometry;
      crop_box_ = VolumeWorldBox(*geometry);
      SendCamera();
    }
  }
  PollCases();
  if (std::optional<v3::RenderSettings> view = connection_->TakeCaseView()) ApplyCaseView(*view);
  if (std::optional<ShownFrame> frame = connection_->TakeFrame()) {
    window_->SetFrame(frame->image);
    const SDL_Rect before = window_->FrameArea();
    window_->SetSlices(frame->slices);
    // Slices came or went: the 3D frame's cell changed size, ask for it.
    if (window_->FrameArea().w != before.w || window_->FrameArea().h != before.h) {
      resize_at_ = SteadyClock::now();
    }
    frame_info_ = std::move(frame->info);
    fps_ = frame->fps;
    if (frame->latency_ms) latency_ms_ = frame->latency_ms;
  }
}

void ViewerApp::ToggleSlices() {
  if (settings_.slices_size() > 0) {
    settings_.clear_slices();
    Notice("slices off");
  } else {
    for (auto [view, orientation] : {std::pair{"axial", v3::SLICE_ORIENTATION_AXIAL},
                                     std::pair{"coronal", v3::SLICE_ORIENTATION_CORONAL},
                                     std::pair{"sagittal", v3::SLICE_ORIENTATION_SAGITTAL}}) {
      v3::SliceSpec* spec = settings_.add_slices();
      spec->set_view(view);
      spec->set_orientation(orientation);
    }
    Notice("slices: axial, coronal, sagittal through the grabbed tissue");
  }
  SendSettings();
}

const v3::SliceGeometry* ViewerApp::SliceGeometryOf(int index) const {
  if (!frame_info_ || index < 0 || index >= frame_info_->slices_size()) return nullptr;
  return &frame_info_->slices(index).geometry();
}

bool ViewerApp::ScrollSliceAt(int window_x, int window_y, double notches) {
  const std::optional<SlicePixel> at = window_->ToSlicePixel(window_x, window_y);
  const v3::SliceGeometry* g = at ? SliceGeometryOf(at->index) : nullptr;
  if (g == nullptr) return false;
  // The pane shows Frame.slices(i), the answer to settings_.slices(i) by its view tag.
  const std::string& view = frame_info_->slices(at->index).view();
  for (v3::SliceSpec& spec : *settings_.mutable_slices()) {
    if (spec.view() != view) continue;
    const double from = spec.has_at_mm() ? spec.at_mm() : g->offset_mm();
    spec.set_at_mm(ScrolledSliceOffset(*g, from, notches));
    SendSettings();
    Notice(StrCat(view, " at ", std::round(spec.at_mm() * 10.0) / 10.0, " mm"));
    return true;
  }
  return false;
}

void ViewerApp::StartSlicePull(const SlicePixel& at) {
  const v3::SliceGeometry* g = SliceGeometryOf(at.index);
  if (g == nullptr || !geometry_) return;
  if (grabbed_) LetGo();
  const glm::dvec3 point = SlicePointMm(*g, at.x, at.y);  // world LPS
  const glm::dvec3 in_volume = geometry_->WorldToPhysical(point);
  const glm::dvec3 extent = geometry_->extent_mm();
  for (int a = 0; a < 3; ++a) {
    if (!(in_volume[a] >= 0.0 && in_volume[a] <= extent[a])) {
      return Notice("nothing to grab there: the point is outside the volume");
    }
  }
  v3::ClientEvent event;
  v3::Vec3* p = event.mutable_grab()->mutable_point_mm();
  p->set_x(point.x);
  p->set_y(point.y);
  p->set_z(point.z);
  connection_->Send(event);
  grabbed_ = true;
  gesture_ = Gesture::kSlicePull;
  pull_slice_ = *g;
  pull_slice_scale_ = at.pixels_per_window_pixel;
  pull_from_x_ = last_x_;  // the press (OnButtonDown)
  pull_from_y_ = last_y_;
}

void ViewerApp::ToggleCropMode() {
  if (!geometry_) return Notice("crop: no volume yet");
  crop_mode_ = !crop_mode_;
  hover_face_.reset();
  if (crop_mode_) {
    *settings_.mutable_crop() = CropBoxToProto(crop_box_);
    Notice("crop box: drag a face to move it (B again: off)");
  } else {
    settings_.clear_crop();
    Notice("crop box off");
  }
  SendSettings();
}

void ViewerApp::ToggleClipPlane() {
  if (!camera_ || !geometry_) return Notice("clip: no volume yet");
  if (settings_.clip_size() > 0) {
    settings_.clear_clip();
    Notice("clip planes off");
  } else {
    *settings_.add_clip() = ClipPlaneFacingCamera(*camera_, *geometry_);
    Notice("clip plane: Shift+drag or PageUp/PageDown move it");
  }
  SendSettings();
}

// Another plane facing the camera through the orbit centre; the moves act on
// the newest. The ray caster takes 16 planes, a crop box counting 6.
void ViewerApp::AddClipPlane() {
  constexpr int kMaxClipPlanes = 10;
  if (!camera_ || !geometry_) return Notice("clip: no volume yet");
  if (settings_.clip_size() >= kMaxClipPlanes) {
    return Notice(StrCat("clip: at most ", kMaxClipPlanes, " planes"));
  }
  *settings_.add_clip() = ClipPlaneFacingCamera(*camera_, *geometry_);
  Notice(StrCat("clip plane ", settings_.clip_size(), ": Shift+drag or PageUp/PageDown move it"));
  SendSettings();
}

void ViewerApp::MoveClipPlane(double delta_mm) {
  if (!geometry_ || settings_.clip_size() == 0) return;
  const int newest = settings_.clip_size() - 1;
  *settings_.mutable_clip(newest) =
      vpm::view::MoveClipPlane(settings_.clip(newest), delta_mm, VolumeWorldBox(*geometry_));
  SendSettings();
}

std::optional<BoxFace> ViewerApp::FaceAt(int window_x, int window_y) const {
  if (!crop_mode_ || !camera_ || !geometry_) return std::nullopt;
  const std::optional<SDL_Point> px = window_->ToFramePixel(window_x, window_y);
  if (!px) return std::nullopt;
  return PickBoxFace(*camera_, *geometry_, crop_box_, px->x, px->y, window_->frame_width(),
                     window_->frame_height());
}

void ViewerApp::Paint() {
  PaintInputs in;
  const ConnectionState state = connection_->state();
  StatusInputs status{state.connected ? fps_ : 0.0, latency_ms_, frame_info_, grab_mode_,
                      grabbed_, settings_.interactive_quality()};
  for (const std::string& line : StatusLines(status)) in.status_lines.push_back(line);
  in.show_help = show_help_;
  if (show_cases_) in.panel_lines = case_panel_.Lines(window_->TextColumns());
  if (!state.connected) in.message = state.message;
  if (SteadyClock::now() < notice_until_) in.notice = notice_;
  if (crop_mode_ && camera_ && geometry_) {
    in.frame_lines = BoxOutline(*camera_, *geometry_, crop_box_,
                                gesture_ == Gesture::kCropFace ? drag_face_ : hover_face_,
                                window_->frame_width(), window_->frame_height());
  }
  window_->Paint(in);
}

void ViewerApp::SendCamera() {
  if (!camera_) return;
  v3::ClientEvent event;
  *event.mutable_camera() = camera_->ToProto();
  connection_->Send(event);
}

void ViewerApp::SendSettings() {
  // The view cut as `vpm render --cut auto`: on unless a crop box or a clip
  // plane says what to show.
  settings_.set_view_cut(view_cut_ && !settings_.has_crop() && settings_.clip_size() == 0);
  v3::ClientEvent event;
  *event.mutable_settings() = settings_;
  connection_->Send(event);
  if (flags_.connection.log_frames) {
    // For tests: what the viewer asked for, world mm.
    std::string line = "settings crop";
    if (settings_.has_crop()) {
      const v3::CropBox& c = settings_.crop();
      for (const v3::Vec3& v : {c.lo_mm(), c.hi_mm()}) {
        line += StrCat(" ", v.x(), " ", v.y(), " ", v.z());
      }
    } else {
      line += " none";
    }
    line += " clip";
    for (const v3::ClipPlane& c : settings_.clip()) line += StrCat(" ", c.offset_mm());
    if (settings_.clip_size() == 0) line += " none";
    line += " at";
    for (const v3::SliceSpec& spec : settings_.slices()) {
      line += spec.has_at_mm() ? StrCat(" ", spec.view(), "=", spec.at_mm())
                               : StrCat(" ", spec.view(), "=auto");
    }
    std::printf("%s\n", line.c_str());
    std::fflush(stdout);
  }
}

void ViewerApp::ToggleCases() {
  show_cases_ = !show_cases_;
  if (!show_cases_) return;
  case_panel_.Clear();
  connection_->ListCases();
}

void ViewerApp::OnCasePanelKey(std::string_view key) {
  const bool was_renaming = case_panel_.renaming();
  const CasePanelRequest request = case_panel_.OnKey(key);
  if (case_panel_.renaming() && !was_renaming) {
    SDL_StartTextInput();
    skip_text_ = true;
  }
  if (!case_panel_.renaming() && was_renaming) skip_text_ = false;
  switch (request.kind) {
    case CasePanelRequest::Kind::kNone: break;
    case CasePanelRequest::Kind::kClose: show_cases_ = false; break;
    case CasePanelRequest::Kind::kOpen:
      show_cases_ = false;
      // Another case may be another volume: the view starts from its own.
      camera_.reset();
      volume_id_.clear();
      connection_->SwitchToCase(request.case_id);
      Notice("opening case " + request.case_id);
      break;
    case CasePanelRequest::Kind::kRename:
      connection_->RenameCase(request.case_id, request.title);
      break;
    case CasePanelRequest::Kind::kDelete: connection_->DeleteCase(request.case_id); break;
  }
}

void ViewerApp::ApplyCaseView(const v3::RenderSettings& view) {
  // The stream started with it (InteractConnection::TakeCaseView): the
  // controls follow, nothing is sent.
  settings_ = WithCaseView(settings_, view);
  crop_mode_ = view.has_crop();
  hover_face_.reset();
  if (crop_mode_) crop_box_ = CropBoxFromProto(view.crop());
  // The view cut is the user's choice only while no crop or clip is on.
  if (!view.has_crop() && view.clip_size() == 0) view_cut_ = view.view_cut();
  Notice(StrCat("the case's view: ", view.mode() == v3::RENDER_MODE_MIP ? "MIP" : "DVR",
                view.has_crop() ? ", crop box" : "", view.clip_size() > 0 ? ", clip planes" : "",
                view.slices_size() > 0 ? ", slices" : ""));
}

void ViewerApp::PollCases() {
  if (auto cases = connection_->TakeCases()) {
    if (cases->ok()) {
      if (flags_.connection.log_frames) std::printf("cases %zu\n", (*cases)->size());
      case_panel_.SetCases(**std::move(cases), connection_->state().case_id);
    } else {
      case_panel_.SetError(std::string(cases->status().message()));
    }
  }
  if (std::optional<std::string> notice = connection_->TakeNotice()) {
    if (flags_.connection.log_frames) std::printf("notice %s\n", notice->c_str());
    // A rename or a delete changed the list: ask for it again.
    if (show_cases_ && (notice->starts_with("case renamed") || notice->starts_with("case deleted"))) {
      connection_->ListCases();
    }
    Notice(*std::move(notice));
  }
  std::fflush(stdout);
}

void ViewerApp::Notice(std::string text) {
  notice_ = std::move(text);
  notice_until_ = SteadyClock::now() + kNoticeTime;
}

double ViewerApp::FramePixelsPerWindowPixel() const {
  const SDL_Rect r = window_->FrameRect();
  return r.w > 0 && window_->frame_width() > 0 ? double(window_->frame_width()) / r.w : 1.0;
}

}  // namespace vpm::view
