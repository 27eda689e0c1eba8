#include "client/view/text_renderer.h"

#include <cstdint>
#include <vector>

#include "client/view/bitmap_font.h"

namespace vpm::view {
namespace {

constexpr int kFirstChar = 32, kLastChar = 126;
constexpr int kCharCount = kLastChar - kFirstChar + 1;

}  // namespace

TextRenderer::TextRenderer(SDL_Renderer* renderer) : renderer_(renderer) {
  const int width = kCharCount * kGlyphAdvance, height = kLineHeight;
  std::vector<uint32_t> pixels(static_cast<size_t>(width) * height, 0u);
  for (int c = kFirstChar; c <= kLastChar; ++c) {
    const auto rows = Glyph(static_cast<char>(c));
    for (int y = 0; y < kGlyphHeight; ++y) {
      for (int x = 0; x < kGlyphWidth; ++x) {
        if (rows[y][x] == '#') pixels[y * width + (c - kFirstChar) * kGlyphAdvance + x] = ~0u;
      }
    }
  }
  atlas_ = SDL_CreateTexture(renderer_, SDL_PIXELFORMAT_RGBA8888, SDL_TEXTUREACCESS_STATIC,
                             width, height);
  if (atlas_ == nullptr) return;  // text is then not drawn; the frames still are
  SDL_UpdateTexture(atlas_, nullptr, pixels.data(), width * 4);
  SDL_SetTextureBlendMode(atlas_, SDL_BLENDMODE_BLEND);
}

TextRenderer::~TextRenderer() {
  if (atlas_ != nullptr) SDL_DestroyTexture(atlas_);
}

void TextRenderer::Draw(int x, int y, std::string_view text, SDL_Color color, int scale) {
  if (atlas_ == nullptr) return;
  SDL_SetTextureColorMod(atlas_, color.r, color.g, color.b);
  SDL_SetTextureAlphaMod(atlas_, color.a);
  for (size_t i = 0; i < text.size(); ++i) {
    int c = static_cast<unsigned char>(text[i]);
    if (c < kFirstChar || c > kLastChar) c = '?';
    const SDL_Rect src{(c - kFirstChar) * kGlyphAdvance, 0, kGlyphAdvance, kLineHeight};
    const SDL_Rect dst{x + static_cast<int>(i) * kGlyphAdvance * scale, y, kGlyphAdvance * scale,
                       kLineHeight * scale};
    SDL_RenderCopy(renderer_, atlas_, &src, &dst);
  }
}

}  // namespace vpm::view
