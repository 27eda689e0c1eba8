// vpm-view's main loop on the SDL thread: window events become camera
// moves, grabs, drags and settings for the connection; frames and
// connection state from it become the picture.
#pragma once

#include <atomic>
#include <chrono>
#include <memory>
#include <optional>
#include <string>

#include <SDL.h>

#include "client/view/case_panel.h"
#include "client/view/clip_plane_drag.h"
#include "client/view/crop_box_drag.h"
#include "client/view/interact_connection.h"
#include "client/view/key_bindings.h"
#include "client/view/view_camera.h"
#include "client/view/view_flags.h"
#include "client/view/viewer_window.h"

namespace vpm::view {

class ViewerApp {
 public:
  explicit ViewerApp(ViewFlags flags);
  ~ViewerApp();
  // Opens the window, connects and runs until quit. Returns the exit code.
  int Run();

 private:
  void HandleEvent(const SDL_Event& event);
  void OnAction(Action action);
  // The actions that change the render settings (view cut, quality while
  // moving, MIP, overlay); false for the others.
  bool OnSettingsAction(Action action);
  // PageDown / PageUp: the slice under the cursor by 1 (Shift: 5) pixels
  // in `sign`'s direction, else the clip plane by as many mm.
  void ScrollByKey(double sign);
  // Back to rest: kept drags and pins dropped.
  void ResetDeformation();
  void OnButtonDown(const SDL_MouseButtonEvent& button);
  void OnButtonUp(const SDL_MouseButtonEvent& button);
  void OnMotion(const SDL_MouseMotionEvent& motion);
  void StartPull(int window_x, int window_y);
  void LetGo(bool keep = false);  // keep: the drag stays (Release.keep)
  void PinAtCursor();
  void RefineAtCursor();
  // Three slices (axial, coronal, sagittal) with every frame, or none.
  void ToggleSlices();
  // Slices: scroll the one under the window point by `notches` pixels;
  // false when no slice is there.
  bool ScrollSliceAt(int window_x, int window_y, double notches);
  // Grab mode, a press on a slice: grab the point of its plane there.
  void StartSlicePull(const SlicePixel& at);
  // The geometry of slice `index` in the newest frame, if it has one.
  const v3::SliceGeometry* SliceGeometryOf(int index) const;
  // Crop box (B) and clip plane (C).
  void ToggleCropMode();
  void ToggleClipPlane();
  void AddClipPlane();
  void MoveClipPlane(double delta_mm);
  // The crop face under the window point, in crop mode.
  std::optional<BoxFace> FaceAt(int window_x, int window_y) const;
  void SaveScreenshot();
  // The cases panel (F2): shown or hidden; its keys and typed text; the
  // list and the outcomes of its calls.
  void ToggleCases();
  void OnCasePanelKey(std::string_view key);
  void PollCases();
  // The kept view of a case just opened (the panel, --case) on the controls.
  void ApplyCaseView(const v3::RenderSettings& view);
  void PollConnection();
  void Paint();
  void SendCamera();
  void SendSettings();
  void Notice(std::string text);
  // Window pixels -> frame pixels (the frame may be drawn scaled).
  double FramePixelsPerWindowPixel() const;

  ViewFlags flags_;
  std::unique_ptr<ViewerWindow> window_;
  std::unique_ptr<InteractConnection> connection_;
  uint32_t wake_event_ = 0;
  std::atomic<bool> wake_pending_{false};
  bool running_ = true;

  std::optional<ViewCamera> camera_;
  std::string volume_id_;
  v3::RenderSettings settings_;
  uint64_t stream_generation_ = 0;

  enum class Gesture { kNone, kOrbit, kPan, kPull, kSlicePull, kCropFace, kClipPlane };
  Gesture gesture_ = Gesture::kNone;
  int last_x_ = 0, last_y_ = 0;        // window pixels of the previous motion
  int pull_from_x_ = 0, pull_from_y_ = 0;  // window pixels where the grab started
  // kSlicePull: the slice's geometry at the press and its image pixels per
  // window pixel; kCropFace: the face and the box at the press; kClipPlane:
  // the plane at the press.
  v3::SliceGeometry pull_slice_;
  double pull_slice_scale_ = 1.0;
  BoxFace drag_face_;
  WorldBox drag_box_start_;
  v3::ClipPlane drag_clip_start_;
  // The modifier keys as of the event being handled: each key event carries
  // them. SDL_GetModState() gives them as of the last pump, which under load
  // has already read later key events (Shift up before the Z of Ctrl+Shift+Z).
  SDL_Keymod event_mod_ = KMOD_NONE;
  bool ShiftHeld() const { return (event_mod_ & KMOD_SHIFT) != 0; }
  bool grab_mode_ = false;
  bool view_cut_ = true;  // the user's choice; SendSettings applies it while no crop or clip is on
  bool crop_mode_ = false;                 // the crop box applies and its faces drag
  WorldBox crop_box_;                      // world mm; the volume's box at first
  std::optional<BoxFace> hover_face_;      // highlighted in the outline
  std::optional<VolumeGeometry> geometry_;
  bool grabbed_ = false;  // the server holds a grab of ours
  bool show_help_ = false;
  bool show_cases_ = false;
  CasePanel case_panel_;
  bool skip_text_ = false;  // the key that starts a rename types a letter too

  std::optional<v3::Frame> frame_info_;
  double fps_ = 0;
  std::optional<double> latency_ms_;
  std::string notice_;
  SteadyClock::time_point notice_until_{};
  std::optional<SteadyClock::time_point> resize_at_;  // when to ask for the new size
  int screenshots_ = 0;
};

}  // namespace vpm::view
