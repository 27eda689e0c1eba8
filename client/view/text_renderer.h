// Draws text with the built-in bitmap font (bitmap_font.h): the glyphs are
// rasterised once into a white texture, tinted per call.
#pragma once

#include <string_view>

#include <SDL.h>

namespace vpm::view {

class TextRenderer {
 public:
  explicit TextRenderer(SDL_Renderer* renderer);
  ~TextRenderer();
  TextRenderer(const TextRenderer&) = delete;
  TextRenderer& operator=(const TextRenderer&) = delete;

  // Draws `text` with its top-left corner at (x, y) window pixels, each font
  // pixel `scale` x `scale` window pixels.
  void Draw(int x, int y, std::string_view text, SDL_Color color, int scale = 1);

 private:
  SDL_Renderer* renderer_;
  SDL_Texture* atlas_ = nullptr;  // one kGlyphAdvance x kLineHeight cell per character 32..126
};

}  // namespace vpm::view
