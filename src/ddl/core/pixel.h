#pragma once
// The pixel a sub-pixel image coordinate falls in. Pixel centres sit at integer coordinates, so
// the pixel is the rounded coordinate; ties round away from zero. Every lookup of a keypoint's
// pixel (the dynamic mask at extraction, the depth, the mask a frame drops features by) uses
// this one rule, so that they all read the same pixel (cvRound rounds ties to even and read the
// next row or column on a third of the ties of pyramid levels 1-7).

#include <cmath>

namespace ddl {

inline int nearest_pixel(float coordinate) { return static_cast<int>(std::lround(coordinate)); }

}  // namespace ddl
