#include "client/view/viewer_app.h"

#include <cstdio>
#include <ctime>
#include <filesystem>
#include <fstream>

#include "client/view/status_text.h"
#include "proto/enum_names.h"

namespace vpm::view {
namespace {

constexpr auto kNoticeTime = std::chrono::milliseconds(2500);
constexpr auto kResizeQuiet = std::chrono::milliseconds(200);  // debounce of window resizes

}  // namespace

ViewerApp::ViewerApp(ViewFlags flags) : flags_(std::move(flags)) {
  settings_.set_mode(RenderModeFromName(flags_.mode).value_or(v2::RENDER_MODE_DVR));
  settings_.set_preset(flags_.preset);
  settings_.set_width(flags_.width);
  settings_.set_height(flags_.height);
  settings_.set_overlay(flags_.overlay);
  settings_.set_encoding(v2::ENCODING_JPEG);
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
  switch (e.type) {
    case SDL_QUIT:
      running_ = false;
      break;
    case SDL_WINDOWEVENT:
      if (e.window.event == SDL_WINDOWEVENT_SIZE_CHANGED) {
        resize_at_ = SteadyClock::now() + kResizeQuiet;
      }
      break;
    case SDL_KEYDOWN:
      if (auto action = ActionForKey(SDL_GetKeyName(e.key.keysym.sym))) OnAction(*action);
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
        camera_->Zoom(e.wheel.direction == SDL_MOUSEWHEEL_FLIPPED ? -e.wheel.y : e.wheel.y);
        SendCamera();
      }
      break;
    default:
      break;
  }
}

void ViewerApp::OnAction(Action action) {
  auto preset = [this](const char* name) {
    settings_.set_mode(v2::RENDER_MODE_DVR);
    settings_.set_preset(name);
    SendSettings();
    Notice(StrCat("DVR ", name));
  };
  switch (action) {
    case Action::kToggleHelp: show_help_ = !show_help_; break;
    case Action::kToggleGrabMode:
      grab_mode_ = !grab_mode_;
      Notice(grab_mode_ ? "grab mode: left drag pulls tissue" : "grab mode off: left drag orbits");
      break;
    case Action::kPresetSoftTissue: preset("ct-soft-tissue"); break;
    case Action::kPresetBone: preset("ct-bone"); break;
    case Action::kPresetVessels: preset("ct-vessels"); break;
    case Action::kPresetMriT1: preset("mri-t1"); break;
    case Action::kMip:
      settings_.set_mode(settings_.mode() == v2::RENDER_MODE_MIP ? v2::RENDER_MODE_DVR
                                                                 : v2::RENDER_MODE_MIP);
      SendSettings();
      Notice(settings_.mode() == v2::RENDER_MODE_MIP ? "MIP" : "DVR");
      break;
    case Action::kToggleSlices: ToggleSlices(); break;
    case Action::kToggleOverlay:
      settings_.set_overlay(!settings_.overlay());
      SendSettings();
      break;
    case Action::kRefineHere: RefineAtCursor(); break;
    case Action::kResetView:
      if (camera_) camera_->Reset(), SendCamera();
      break;
    case Action::kResetDeformation:
      if (grabbed_) LetGo();
      gesture_ = Gesture::kNone;
      Notice("deformation reset");
      break;
    case Action::kScreenshot: SaveScreenshot(); break;
    case Action::kQuit: running_ = false; break;
  }
}

void ViewerApp::OnButtonDown(const SDL_MouseButtonEvent& b) {
  last_x_ = b.x;
  last_y_ = b.y;
  if (gesture_ != Gesture::kNone) return;
  if (b.button == SDL_BUTTON_LEFT) {
    if (grab_mode_) return StartPull(b.x, b.y);
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
  if (gesture_ == Gesture::kPull) {
    if (SDL_GetModState() & KMOD_SHIFT) {
      Notice("pull kept: X lets go");
    } else {
      LetGo();
    }
  }
  gesture_ = Gesture::kNone;
}

void ViewerApp::OnMotion(const SDL_MouseMotionEvent& m) {
  const double dx = m.x - last_x_, dy = m.y - last_y_;
  last_x_ = m.x;
  last_y_ = m.y;
  if (!camera_ || gesture_ == Gesture::kNone) return;
  const double scale = FramePixelsPerWindowPixel();
  const int fw = settings_.width(), fh = settings_.height();
  if (gesture_ == Gesture::kOrbit) {
    camera_->Orbit(dx, dy);
    SendCamera();
  } else if (gesture_ == Gesture::kPan) {
    camera_->Pan(dx * scale, dy * scale, fw, fh);
    SendCamera();
  } else if (gesture_ == Gesture::kPull && grabbed_) {
    const glm::dvec3 offset = camera_->DragOffsetMm((m.x - pull_from_x_) * scale,
                                                    (m.y - pull_from_y_) * scale, fw, fh);
    v2::ClientEvent event;
    event.mutable_drag()->mutable_offset_mm()->set_x(offset.x);
    event.mutable_drag()->mutable_offset_mm()->set_y(offset.y);
    event.mutable_drag()->mutable_offset_mm()->set_z(offset.z);
    connection_->Send(event);
  }
}

void ViewerApp::StartPull(int window_x, int window_y) {
  if (!camera_) return;
  if (grabbed_) LetGo();  // a kept pull ends when a new one starts
  const std::optional<SDL_Point> px = window_->ToFramePixel(window_x, window_y);
  if (!px || !camera_->PickPoint(px->x, px->y, window_->frame_width(), window_->frame_height())) {
    Notice("nothing to grab there: the point is outside the volume");
    return;
  }
  v2::ClientEvent event;
  v2::Grab* grab = event.mutable_grab();
  grab->set_pick(true);
  grab->set_pixel_x(px->x);
  grab->set_pixel_y(px->y);
  connection_->Send(event);
  grabbed_ = true;
  gesture_ = Gesture::kPull;
  pull_from_x_ = window_x;
  pull_from_y_ = window_y;
}

void ViewerApp::LetGo() {
  v2::ClientEvent event;
  event.mutable_release();
  connection_->Send(event);
  grabbed_ = false;
}

void ViewerApp::RefineAtCursor() {
  int x = 0, y = 0;
  SDL_GetMouseState(&x, &y);
  const std::optional<SDL_Point> px = window_->ToFramePixel(x, y);
  const std::optional<glm::dvec3> point =
      (camera_ && px) ? camera_->PickPoint(px->x, px->y, window_->frame_width(),
                                           window_->frame_height())
                      : std::nullopt;
  if (!point) return Notice("refine: put the cursor over the volume");
  grabbed_ = false;
  gesture_ = Gesture::kNone;
  connection_->RefineAt(*point);
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
    if (gesture_ == Gesture::kPull) gesture_ = Gesture::kNone;
  }
  if (state.volume && state.volume->volume_id() != volume_id_) {
    volume_id_ = state.volume->volume_id();
    auto geometry = GeometryFromProto(*state.volume);
    if (!geometry.ok()) {
      Notice(std::string(geometry.status().message()));
    } else if (!camera_) {
      // A restarted server gives the same volume a new id: the view stays.
      camera_.emplace(*geometry);
      SendCamera();
    }
  }
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
    for (auto [view, orientation] : {std::pair{"axial", v2::SLICE_ORIENTATION_AXIAL},
                                     std::pair{"coronal", v2::SLICE_ORIENTATION_CORONAL},
                                     std::pair{"sagittal", v2::SLICE_ORIENTATION_SAGITTAL}}) {
      v2::SliceSpec* spec = settings_.add_slices();
      spec->set_view(view);
      spec->set_orientation(orientation);
    }
    Notice("slices: axial, coronal, sagittal through the grabbed tissue");
  }
  SendSettings();
}

void ViewerApp::Paint() {
  PaintInputs in;
  const ConnectionState state = connection_->state();
  StatusInputs status{state.connected ? fps_ : 0.0, latency_ms_, frame_info_, grab_mode_,
                      grabbed_};
  for (const std::string& line : StatusLines(status)) in.status_lines.push_back(line);
  in.show_help = show_help_;
  if (!state.connected) in.message = state.message;
  if (SteadyClock::now() < notice_until_) in.notice = notice_;
  window_->Paint(in);
}

void ViewerApp::SendCamera() {
  if (!camera_) return;
  v2::ClientEvent event;
  *event.mutable_camera() = camera_->ToProto();
  connection_->Send(event);
}

void ViewerApp::SendSettings() {
  v2::ClientEvent event;
  *event.mutable_settings() = settings_;
  connection_->Send(event);
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
