// The SDL window: the newest frame scaled into the frame area, the status
// bar under it, the help overlay and the connection message on top.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include <SDL.h>

#include "client/view/crop_box_drag.h"
#include "client/view/text_renderer.h"
#include "server/common/status.h"
#include "server/raycast/frame_encoder.h"

namespace vpm::view {

// Height of the status bar under the frame area, window pixels.
int StatusBarHeight();

struct PaintInputs {
  std::vector<std::string> status_lines;
  bool show_help = false;
  // The cases panel (F2) while shown: its lines, drawn over the frame.
  std::vector<std::string> panel_lines;
  std::string message;  // shown in a red banner when not empty (connection lost, errors)
  std::string notice;   // shown briefly in a grey banner (screenshot saved, ...)
  // Lines over the 3D frame, frame pixels (the crop box's outline): on_face
  // ones (the face the pointer is on) yellow, the others light grey.
  std::vector<ScreenSegment> frame_lines;
};

// A point on a slice pane: which slice (0..2, in Frame.slices order), where
// on its image (continuous pixels, row 0 at the top) and how many image
// pixels one window pixel spans there.
struct SlicePixel {
  int index = 0;
  double x = 0.0, y = 0.0;
  double pixels_per_window_pixel = 1.0;
};

class ViewerWindow {
 public:
  // A resizable window whose frame area is width x height pixels.
  static Result<std::unique_ptr<ViewerWindow>> Create(const std::string& title, int width,
                                                      int height);
  ~ViewerWindow();
  ViewerWindow(const ViewerWindow&) = delete;
  ViewerWindow& operator=(const ViewerWindow&) = delete;

  // Replaces the frame shown (RGBA8, row 0 at the top).
  void SetFrame(const DecodedImage& image);
  // The slices shown beside it (at most 3): with any, the window is a 2 x 2
  // grid, the frame top left and the slices in the other cells in order.
  void SetSlices(const std::vector<DecodedImage>& slices);
  void Paint(const PaintInputs& in);

  // The frame area (window minus the status bar; its top-left quarter
  // while slices show), window pixels.
  SDL_Rect FrameArea() const;
  // Characters of the panel font that fit across the frame area.
  size_t TextColumns() const;
  // Where the current frame is drawn (aspect kept, centred in the area).
  SDL_Rect FrameRect() const;
  // Window pixel -> pixel of the current frame; empty outside it.
  std::optional<SDL_Point> ToFramePixel(int window_x, int window_y) const;
  // Window pixel -> point of the slice shown under it; empty elsewhere.
  std::optional<SlicePixel> ToSlicePixel(int window_x, int window_y) const;
  int frame_width() const { return frame_width_; }
  int frame_height() const { return frame_height_; }

  // The window's current picture, RGBA8, row 0 at the top.
  Result<DecodedImage> ReadPixels() const;
  uint32_t id() const { return SDL_GetWindowID(window_); }

 private:
  ViewerWindow() = default;
  void PaintBanner(const std::string& text, SDL_Color fill, int y);
  // Lines over the top of the frame area on a dark panel.
  void PaintPanel(const std::vector<std::string>& lines, SDL_Color color);
  void PaintFrameLines(const std::vector<ScreenSegment>& lines);
  // Where slice i is drawn (cells 1..3 of the 2 x 2 grid, aspect kept).
  SDL_Rect SliceRect(size_t i) const;

  SDL_Window* window_ = nullptr;
  SDL_Renderer* renderer_ = nullptr;
  std::unique_ptr<TextRenderer> text_;
  // `texture` (w x h pixels) scaled into `area`, aspect kept, centred.
  static SDL_Rect Fit(const SDL_Rect& area, int w, int h);
  // The whole area under the window's frames (window minus the status bar).
  SDL_Rect ImageArea() const;

  SDL_Texture* frame_ = nullptr;
  int frame_width_ = 0, frame_height_ = 0;  // pixels of the frame texture
  struct SliceTexture {
    SDL_Texture* texture = nullptr;
    int width = 0, height = 0;
  };
  std::vector<SliceTexture> slices_;
};

}  // namespace vpm::view
