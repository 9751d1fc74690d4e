#pragma once
// Procedural textures for the synthetic rooms: seeded, deterministic, rich in corners at every
// scale an ORB pyramid looks at (1.2^0..1.2^7), and free of periodic patterns (ORB matching
// confuses repeated structures). Sizes are in texels; `texel_m` is the metric size of one texel so
// physical features (planks, books, letters) keep real-world sizes whatever the surface size.
// Pure functions of their arguments (the Rng is advanced); no global state.

#include <opencv2/core.hpp>

#include "ddl/synthetic/random.h"

namespace ddl::synthetic {

/// Multi-octave value noise (cubic-interpolated random grids), zero mean, roughly in [-1, 1].
/// Octave cell sizes go from `largest_cell_px` down to `smallest_cell_px` halving each time, each
/// octave weighted by `persistence` relative to the previous one. CV_32FC1.
cv::Mat fractal_noise(cv::Size size, Rng& rng, double largest_cell_px, double smallest_cell_px,
                      double persistence);

/// A painted wall: plaster noise, a dense non-periodic scatter of small motifs, picture frames,
/// notes and a baseboard along the bottom edge (texture rows grow downwards = towards the floor).
cv::Mat make_wall_texture(cv::Size size, double texel_m, Rng& rng);
/// A wooden floor of planks of random width/length, grain, gaps and knots, plus a patterned rug.
cv::Mat make_floor_texture(cv::Size size, double texel_m, Rng& rng);
/// Ceiling tiles with speckles, stains and light panels (each tile different).
cv::Mat make_ceiling_texture(cv::Size size, double texel_m, Rng& rng);
/// Wood veneer for furniture sides; `clutter` adds papers, pens and a keyboard (desk tops).
cv::Mat make_wood_texture(cv::Size size, double texel_m, Rng& rng, bool clutter);
/// The front of a bookshelf: shelf boards and rows of book spines with titles.
cv::Mat make_bookshelf_texture(cv::Size size, double texel_m, Rng& rng);
/// Cardboard with tape, printed labels, barcodes and arrows.
cv::Mat make_cardboard_texture(cv::Size size, double texel_m, Rng& rng);
/// An abstract poster: shapes, a title and text blocks.
cv::Mat make_poster_texture(cv::Size size, Rng& rng);
/// A plain coloured person silhouette (head, torso, arms, legs) with its coverage mask, used when
/// no photographs of people are available. `bgr` is CV_8UC3, `alpha` CV_8UC1 (255 = person).
void make_person_silhouette(cv::Size size, Rng& rng, cv::Mat& bgr, cv::Mat& alpha);

}  // namespace ddl::synthetic
