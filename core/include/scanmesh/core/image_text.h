// Text on pictures: a built-in 5 x 7 pixel font for legends, region names and view titles.
#pragma once

#include <string>

#include "scanmesh/core/image.h"

namespace scanmesh {

//! Draws text with its top-left corner at (x, y): digits, upper-case letters (lower case is
//! drawn upper case, except 'e' and 'm' for units and exponents), . , - + [ ] ( ) / = : ^ _ %
//! | < > * ' # and space; anything else as '?'. Pixels outside the image are skipped.
void draw_text(Image8& image, int x, int y, const std::string& text, Rgb8 color, int scale = 1);
//! The same text on a filled box one `scale` unit wider on each side (readable over a picture).
void draw_label(Image8& image, int x, int y, const std::string& text, Rgb8 ink, Rgb8 background,
                int scale = 1);
//! Width and height in pixels of `text` drawn at `scale`.
int text_width(const std::string& text, int scale = 1);
int text_height(int scale = 1);

}  // namespace scanmesh
