#include "client/view/viewer_window.h"

#include <algorithm>

#include "client/view/bitmap_font.h"
#include "client/view/key_bindings.h"
#include "client/view/status_text.h"

namespace vpm::view {
namespace {

constexpr int kPad = 3;  // window pixels around text

}  // namespace

int StatusBarHeight() { return kStatusLineCount * kLineHeight + 2 * kPad; }

Result<std::unique_ptr<ViewerWindow>> ViewerWindow::Create(const std::string& title, int width,
                                                           int height) {
  std::unique_ptr<ViewerWindow> w(new ViewerWindow());
  w->window_ = SDL_CreateWindow(title.c_str(), SDL_WINDOWPOS_UNDEFINED, SDL_WINDOWPOS_UNDEFINED,
                                width, height + StatusBarHeight(), SDL_WINDOW_RESIZABLE);
  if (w->window_ == nullptr) return absl::UnavailableError(StrCat("SDL window: ", SDL_GetError()));
  // Software rendering: works on any X server (Xvfb included), and frames
  // are small next to what the server spends on them.
  w->renderer_ = SDL_CreateRenderer(w->window_, -1, SDL_RENDERER_SOFTWARE);
  if (w->renderer_ == nullptr) {
    return absl::UnavailableError(StrCat("SDL renderer: ", SDL_GetError()));
  }
  SDL_SetRenderDrawBlendMode(w->renderer_, SDL_BLENDMODE_BLEND);
  w->text_ = std::make_unique<TextRenderer>(w->renderer_);
  return w;
}

ViewerWindow::~ViewerWindow() {
  text_.reset();
  if (frame_ != nullptr) SDL_DestroyTexture(frame_);
  for (const SliceTexture& s : slices_) SDL_DestroyTexture(s.texture);
  if (renderer_ != nullptr) SDL_DestroyRenderer(renderer_);
  if (window_ != nullptr) SDL_DestroyWindow(window_);
}

void ViewerWindow::SetFrame(const DecodedImage& image) {
  if (frame_ == nullptr || image.width != frame_width_ || image.height != frame_height_) {
    if (frame_ != nullptr) SDL_DestroyTexture(frame_);
    // ABGR8888 is R, G, B, A in memory on little-endian machines.
    frame_ = SDL_CreateTexture(renderer_, SDL_PIXELFORMAT_ABGR8888, SDL_TEXTUREACCESS_STREAMING,
                               image.width, image.height);
    frame_width_ = frame_ != nullptr ? image.width : 0;
    frame_height_ = frame_ != nullptr ? image.height : 0;
    if (frame_ == nullptr) return;
    SDL_SetTextureScaleMode(frame_, SDL_ScaleModeLinear);
  }
  SDL_UpdateTexture(frame_, nullptr, image.rgba.data(), image.width * 4);
}

void ViewerWindow::SetSlices(const std::vector<DecodedImage>& slices) {
  const size_t n = std::min<size_t>(slices.size(), 3);
  while (slices_.size() > n) {
    SDL_DestroyTexture(slices_.back().texture);
    slices_.pop_back();
  }
  slices_.resize(n);
  for (size_t i = 0; i < n; ++i) {
    SliceTexture& s = slices_[i];
    const DecodedImage& image = slices[i];
    if (s.texture == nullptr || s.width != image.width || s.height != image.height) {
      if (s.texture != nullptr) SDL_DestroyTexture(s.texture);
      s.texture = SDL_CreateTexture(renderer_, SDL_PIXELFORMAT_ABGR8888,
                                    SDL_TEXTUREACCESS_STREAMING, image.width, image.height);
      s.width = image.width;
      s.height = image.height;
      if (s.texture == nullptr) continue;
      SDL_SetTextureScaleMode(s.texture, SDL_ScaleModeLinear);
    }
    SDL_UpdateTexture(s.texture, nullptr, image.rgba.data(), image.width * 4);
  }
}

SDL_Rect ViewerWindow::ImageArea() const {
  int w = 0, h = 0;
  SDL_GetRendererOutputSize(renderer_, &w, &h);
  return {0, 0, w, std::max(1, h - StatusBarHeight())};
}

SDL_Rect ViewerWindow::FrameArea() const {
  const SDL_Rect all = ImageArea();
  if (slices_.empty()) return all;
  return {0, 0, std::max(1, all.w / 2), std::max(1, all.h / 2)};
}

SDL_Rect ViewerWindow::Fit(const SDL_Rect& area, int width, int height) {
  if (width <= 0 || height <= 0) return area;
  const double scale = std::min(double(area.w) / width, double(area.h) / height);
  const int w = std::max(1, int(width * scale + 0.5));
  const int h = std::max(1, int(height * scale + 0.5));
  return {area.x + (area.w - w) / 2, area.y + (area.h - h) / 2, w, h};
}

SDL_Rect ViewerWindow::FrameRect() const {
  return Fit(FrameArea(), frame_width_, frame_height_);
}

std::optional<SDL_Point> ViewerWindow::ToFramePixel(int window_x, int window_y) const {
  if (frame_ == nullptr) return std::nullopt;
  const SDL_Rect r = FrameRect();
  if (window_x < r.x || window_y < r.y || window_x >= r.x + r.w || window_y >= r.y + r.h) {
    return std::nullopt;
  }
  return SDL_Point{int(double(window_x - r.x) * frame_width_ / r.w),
                   int(double(window_y - r.y) * frame_height_ / r.h)};
}

SDL_Rect ViewerWindow::SliceRect(size_t i) const {
  const SDL_Rect cell = FrameArea();
  // Cells 1, 2, 3 of the 2 x 2 grid: top right, bottom left, bottom right.
  const int k = int(i) + 1;
  const SDL_Rect area{(k % 2) * cell.w, (k / 2) * cell.h, cell.w, cell.h};
  return Fit(area, slices_[i].width, slices_[i].height);
}

std::optional<SlicePixel> ViewerWindow::ToSlicePixel(int window_x, int window_y) const {
  for (size_t i = 0; i < slices_.size(); ++i) {
    if (slices_[i].texture == nullptr) continue;
    const SDL_Rect r = SliceRect(i);
    if (window_x < r.x || window_y < r.y || window_x >= r.x + r.w || window_y >= r.y + r.h) {
      continue;
    }
    const double scale = double(slices_[i].width) / r.w;
    return SlicePixel{int(i), (window_x - r.x + 0.5) * scale, (window_y - r.y + 0.5) * scale,
                      scale};
  }
  return std::nullopt;
}

void ViewerWindow::PaintFrameLines(const std::vector<ScreenSegment>& lines) {
  if (lines.empty() || frame_width_ <= 0 || frame_height_ <= 0) return;
  const SDL_Rect r = FrameRect();
  const double sx = double(r.w) / frame_width_, sy = double(r.h) / frame_height_;
  SDL_RenderSetClipRect(renderer_, &r);
  for (bool face : {false, true}) {  // the highlighted face on top
    if (face) SDL_SetRenderDrawColor(renderer_, 255, 220, 0, 255);
    else SDL_SetRenderDrawColor(renderer_, 200, 200, 200, 200);
    for (const ScreenSegment& l : lines) {
      if (l.on_face != face) continue;
      SDL_RenderDrawLineF(renderer_, float(r.x + l.a.x * sx), float(r.y + l.a.y * sy),
                          float(r.x + l.b.x * sx), float(r.y + l.b.y * sy));
    }
  }
  SDL_RenderSetClipRect(renderer_, nullptr);
}

void ViewerWindow::Paint(const PaintInputs& in) {
  SDL_SetRenderDrawColor(renderer_, 0, 0, 0, 255);
  SDL_RenderClear(renderer_);
  if (frame_ != nullptr) {
    const SDL_Rect dst = FrameRect();
    SDL_RenderCopy(renderer_, frame_, nullptr, &dst);
  }
  PaintFrameLines(in.frame_lines);
  for (size_t i = 0; i < slices_.size(); ++i) {
    if (slices_[i].texture == nullptr) continue;
    const SDL_Rect dst = SliceRect(i);
    SDL_RenderCopy(renderer_, slices_[i].texture, nullptr, &dst);
  }
  const SDL_Rect area = ImageArea();
  SDL_Rect bar{0, area.h, area.w, StatusBarHeight()};
  SDL_SetRenderDrawColor(renderer_, 32, 32, 40, 255);
  SDL_RenderFillRect(renderer_, &bar);
  for (size_t i = 0; i < in.status_lines.size(); ++i) {
    text_->Draw(kPad, area.h + kPad + int(i) * kLineHeight, in.status_lines[i],
                {220, 220, 220, 255});
  }
  if (in.show_help) PaintPanel(HelpLines(), {255, 230, 120, 255});
  if (!in.panel_lines.empty()) PaintPanel(in.panel_lines, {200, 235, 255, 255});
  if (!in.notice.empty()) PaintBanner(in.notice, {60, 60, 70, 230}, area.h - 2 * kLineHeight);
  if (!in.message.empty()) PaintBanner(in.message, {170, 20, 20, 235}, area.h / 2 - kLineHeight);
  SDL_RenderPresent(renderer_);
}

// A full-width band with `text` word-wrapped into it.
void ViewerWindow::PaintBanner(const std::string& text, SDL_Color fill, int y) {
  const SDL_Rect area = FrameArea();
  const size_t per_line = std::max<size_t>(8, size_t((area.w - 2 * kPad) / kGlyphAdvance));
  std::vector<std::string> lines;
  std::string line;
  size_t start = 0;
  while (start < text.size()) {
    size_t end = text.find(' ', start);
    if (end == std::string::npos) end = text.size();
    std::string word = text.substr(start, end - start);
    while (word.size() > per_line) {  // a word longer than a line is cut
      if (!line.empty()) lines.push_back(std::move(line)), line.clear();
      lines.push_back(word.substr(0, per_line));
      word.erase(0, per_line);
    }
    if (!line.empty() && line.size() + 1 + word.size() > per_line) {
      lines.push_back(std::move(line));
      line.clear();
    }
    line += (line.empty() ? "" : " ") + word;
    start = end + 1;
  }
  if (!line.empty()) lines.push_back(line);
  const int height = int(lines.size()) * kLineHeight + 2 * kPad;
  y = std::clamp(y, 0, std::max(0, area.h - height));
  SDL_Rect band{0, y, area.w, height};
  SDL_SetRenderDrawColor(renderer_, fill.r, fill.g, fill.b, fill.a);
  SDL_RenderFillRect(renderer_, &band);
  for (size_t i = 0; i < lines.size(); ++i) {
    text_->Draw(kPad, y + kPad + int(i) * kLineHeight, lines[i], {255, 255, 255, 255});
  }
}

void ViewerWindow::PaintPanel(const std::vector<std::string>& lines, SDL_Color color) {
  const SDL_Rect area = FrameArea();
  SDL_Rect panel{0, 0, area.w, std::min(area.h, int(lines.size()) * kLineHeight + 2 * kPad)};
  SDL_SetRenderDrawColor(renderer_, 0, 0, 0, 200);
  SDL_RenderFillRect(renderer_, &panel);
  for (size_t i = 0; i < lines.size(); ++i) {
    text_->Draw(kPad, kPad + int(i) * kLineHeight, lines[i], color);
  }
}

size_t ViewerWindow::TextColumns() const {
  return size_t(std::max(8, (FrameArea().w - 2 * kPad) / kGlyphAdvance));
}

Result<DecodedImage> ViewerWindow::ReadPixels() const {
  DecodedImage image;
  SDL_GetRendererOutputSize(renderer_, &image.width, &image.height);
  image.rgba.resize(size_t(image.width) * image.height * 4);
  if (SDL_RenderReadPixels(renderer_, nullptr, SDL_PIXELFORMAT_ABGR8888, image.rgba.data(),
                           image.width * 4) != 0) {
    return absl::InternalError(StrCat("reading the window: ", SDL_GetError()));
  }
  return image;
}

}  // namespace vpm::view
