// A tiny built-in bitmap font (5 x 7 pixels a glyph, capitals, digits and
// ASCII punctuation) so the viewer needs no font files or SDL_ttf. Lower-case
// letters are drawn as capitals; characters without a glyph as '?'.
#pragma once

#include <span>
#include <string_view>

namespace vpm::view {

inline constexpr int kGlyphWidth = 5;    // pixels
inline constexpr int kGlyphHeight = 7;   // pixels
inline constexpr int kGlyphAdvance = 6;  // pixels from one character to the next
inline constexpr int kLineHeight = 9;    // pixels from one line to the next

// The glyph of c: kGlyphHeight rows of kGlyphWidth characters, '#' for a lit
// pixel and '.' for an unlit one, top row first.
std::span<const std::string_view> Glyph(char c);
// Whether c has a glyph of its own (after folding lower case).
bool HasGlyph(char c);
// Width in pixels of `text` on one line at scale 1 (no trailing gap).
int TextWidth(std::string_view text);

}  // namespace vpm::view
