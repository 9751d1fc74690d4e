#include "ddl/synthetic/procedural.h"

#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>
#include <string>
#include <vector>

namespace ddl::synthetic {
namespace {

constexpr double kPi = 3.14159265358979323846;

int px(double metres, double texel_m) { return std::max(1, static_cast<int>(metres / texel_m)); }

cv::Scalar random_color(Rng& rng, int lo, int hi) {
  return {rng.uniform(lo, hi), rng.uniform(lo, hi), rng.uniform(lo, hi)};
}

/// A saturated colour: one channel high, one low, one anywhere.
cv::Scalar vivid_color(Rng& rng) {
  double c[3] = {rng.uniform(0, 90), rng.uniform(150, 255), rng.uniform(0, 255)};
  for (int i = 2; i > 0; --i) std::swap(c[i], c[rng.uniform_int(0, i)]);
  return {c[0], c[1], c[2]};
}

cv::Scalar shifted(const cv::Scalar& c, double delta) {
  return {std::clamp(c[0] + delta, 0.0, 255.0), std::clamp(c[1] + delta, 0.0, 255.0),
          std::clamp(c[2] + delta, 0.0, 255.0)};
}

std::string random_word(Rng& rng, int min_len, int max_len, bool capital) {
  static constexpr char kLetters[] = "abcdefghijklmnopqrstuvwxyzeeaaoitn";
  const int n = rng.uniform_int(min_len, max_len);
  std::string word;
  for (int i = 0; i < n; ++i) {
    word += kLetters[rng.uniform_int(0, static_cast<int>(sizeof(kLetters)) - 2)];
  }
  if (capital && !word.empty()) word[0] = static_cast<char>(word[0] - 'a' + 'A');
  return word;
}

std::string random_line(Rng& rng, int words) {
  std::string line;
  for (int i = 0; i < words; ++i) {
    if (i) line += ' ';
    line += random_word(rng, 2, 8, i == 0 || rng.uniform() < 0.2);
  }
  if (rng.uniform() < 0.3) line += ' ' + std::to_string(rng.uniform_int(1, 2024));
  return line;
}

int random_font(Rng& rng) {
  static constexpr int kFonts[] = {cv::FONT_HERSHEY_SIMPLEX, cv::FONT_HERSHEY_DUPLEX,
                                   cv::FONT_HERSHEY_COMPLEX, cv::FONT_HERSHEY_TRIPLEX,
                                   cv::FONT_HERSHEY_PLAIN};
  return kFonts[rng.uniform_int(0, 4)];
}

/// Text whose cap height is about `height_px`.
void put_text(cv::Mat& img, const std::string& text, cv::Point origin, double height_px, int font,
              const cv::Scalar& color) {
  const double scale = std::max(0.2, height_px / 22.0);
  const int thickness = std::max(1, static_cast<int>(std::lround(scale * 1.6)));
  cv::putText(img, text, origin, font, scale, color, thickness, cv::LINE_AA);
}

/// Paragraph of text lines filling a rectangle.
void text_block(cv::Mat& img, cv::Rect r, double line_px, Rng& rng, const cv::Scalar& color) {
  const int font = random_font(rng);
  for (double y = r.y + line_px; y < r.y + r.height; y += line_px * 1.6) {
    const int words = std::max(1, static_cast<int>(r.width / (line_px * 3.5)));
    cv::Point org(r.x, static_cast<int>(y));
    put_text(img, random_line(rng, rng.uniform_int(std::max(1, words / 2), words)), org, line_px,
             font, color);
  }
}

/// Adds `amplitude` * noise to every channel (noise broadcast over BGR), saturating.
void add_noise(cv::Mat& img, const cv::Mat& noise, double amplitude) {
  cv::Mat n3;
  cv::Mat scaled = noise * amplitude;
  cv::merge(std::vector<cv::Mat>{scaled, scaled, scaled}, n3);
  cv::Mat f;
  img.convertTo(f, CV_32FC3);
  f += n3;
  f.convertTo(img, CV_8UC3);
}

/// Multiplies the image by (1 + amplitude * noise) per channel pair, a colour mottling.
void add_tint_noise(cv::Mat& img, Rng& rng, double cell_px, double amplitude) {
  std::vector<cv::Mat> channels;
  cv::Mat f;
  img.convertTo(f, CV_32FC3);
  cv::split(f, channels);
  for (auto& ch : channels) {
    const cv::Mat n = fractal_noise(img.size(), rng, cell_px, cell_px / 4, 0.5);
    ch = ch.mul(1.0f + amplitude * n);
  }
  cv::merge(channels, f);
  f.convertTo(img, CV_8UC3);
}

/// A small motif at p of size s: circle, ring, square, cross, leaf or stroke.
void motif(cv::Mat& img, cv::Point p, int s, const cv::Scalar& c, Rng& rng) {
  switch (rng.uniform_int(0, 5)) {
    case 0:
      cv::circle(img, p, s / 2, c, cv::FILLED, cv::LINE_AA);
      break;
    case 1:
      cv::circle(img, p, s / 2, c, std::max(1, s / 8), cv::LINE_AA);
      break;
    case 2: {
      cv::RotatedRect rr(p, cv::Size2f(s, s * rng.uniform(0.3, 1.0)), rng.uniform(0, 180));
      cv::Point2f v[4];
      rr.points(v);
      std::vector<cv::Point> pts(v, v + 4);
      cv::fillConvexPoly(img, pts, c, cv::LINE_AA);
      break;
    }
    case 3: {
      const int t = std::max(1, s / 6);
      cv::line(img, p - cv::Point(s / 2, 0), p + cv::Point(s / 2, 0), c, t, cv::LINE_AA);
      cv::line(img, p - cv::Point(0, s / 2), p + cv::Point(0, s / 2), c, t, cv::LINE_AA);
      break;
    }
    case 4:
      cv::ellipse(img, p, cv::Size(s / 2, std::max(1, s / 5)), rng.uniform(0, 180), 0, 360, c,
                  cv::FILLED, cv::LINE_AA);
      break;
    default: {
      std::vector<cv::Point> pts;
      cv::Point q = p;
      double a = rng.uniform(0, 2 * kPi);
      for (int i = 0; i < 5; ++i) {
        pts.push_back(q);
        a += rng.uniform(-1.2, 1.2);
        q +=
            cv::Point(static_cast<int>(std::cos(a) * s / 3), static_cast<int>(std::sin(a) * s / 3));
      }
      cv::polylines(img, pts, false, c, std::max(1, s / 10), cv::LINE_AA);
    }
  }
}

/// Abstract art inside a rectangle (for picture frames and posters).
void abstract_art(cv::Mat& img, cv::Rect r, Rng& rng) {
  cv::rectangle(img, r, random_color(rng, 30, 230), cv::FILLED);
  const int n = rng.uniform_int(6, 16);
  for (int i = 0; i < n; ++i) {
    const cv::Point p(r.x + rng.uniform_int(0, r.width), r.y + rng.uniform_int(0, r.height));
    const int s =
        std::max(3, static_cast<int>(std::min(r.width, r.height) * rng.uniform(0.1, 0.6)));
    const cv::Scalar c = vivid_color(rng);
    if (rng.uniform() < 0.4) {
      std::vector<cv::Point> tri = {p, p + cv::Point(s, rng.uniform_int(-s, s)),
                                    p + cv::Point(rng.uniform_int(-s, s), s)};
      cv::fillConvexPoly(img, tri, c, cv::LINE_AA);
    } else {
      motif(img, p, s, c, rng);
    }
  }
}

}  // namespace

cv::Mat fractal_noise(cv::Size size, Rng& rng, double largest_cell_px, double smallest_cell_px,
                      double persistence) {
  cv::Mat sum(size, CV_32FC1, cv::Scalar(0));
  double weight = 1.0;
  double total = 0.0;
  for (double cell = largest_cell_px; cell >= std::max(1.0, smallest_cell_px) - 1e-9; cell *= 0.5) {
    const int gw = std::max(2, static_cast<int>(std::ceil(size.width / cell)) + 1);
    const int gh = std::max(2, static_cast<int>(std::ceil(size.height / cell)) + 1);
    cv::Mat grid(gh, gw, CV_32FC1);
    for (int y = 0; y < gh; ++y) {
      auto* row = grid.ptr<float>(y);
      for (int x = 0; x < gw; ++x) row[x] = static_cast<float>(rng.uniform(-1.0, 1.0));
    }
    cv::Mat up;
    cv::resize(grid, up, size, 0, 0, cell >= 2.0 ? cv::INTER_CUBIC : cv::INTER_NEAREST);
    cv::scaleAdd(up, weight, sum, sum);
    total += weight;
    weight *= persistence;
  }
  sum *= 1.0 / std::max(total * 0.6, 1e-9);
  return sum;
}

cv::Mat make_wall_texture(cv::Size size, double texel_m, Rng& rng) {
  const cv::Scalar base = random_color(rng, 150, 225);
  cv::Mat img(size, CV_8UC3, base);
  add_noise(img, fractal_noise(size, rng, px(0.8, texel_m), 2, 0.65), 28.0);
  add_tint_noise(img, rng, px(1.0, texel_m), 0.12);
  // Dense scatter of small motifs (a patterned wallpaper without a repeat).
  const double area_m2 = size.area() * texel_m * texel_m;
  const int motifs = static_cast<int>(area_m2 / (0.075 * 0.075));
  const cv::Scalar ink = shifted(base, rng.uniform() < 0.5 ? -90 : -60);
  for (int i = 0; i < motifs; ++i) {
    const cv::Point p(rng.uniform_int(0, size.width - 1), rng.uniform_int(0, size.height - 1));
    const int s = px(rng.uniform(0.012, 0.07), texel_m);
    const cv::Scalar c =
        rng.uniform() < 0.6 ? shifted(ink, rng.uniform(-30, 30)) : vivid_color(rng);
    motif(img, p, s, c, rng);
  }
  // Picture frames and notes.
  const int frames = std::max(2, static_cast<int>(area_m2 / 1.6));
  for (int i = 0; i < frames; ++i) {
    const int w = px(rng.uniform(0.15, 0.5), texel_m);
    const int h = px(rng.uniform(0.15, 0.45), texel_m);
    const cv::Rect r(rng.uniform_int(0, std::max(0, size.width - w)),
                     rng.uniform_int(0, std::max(0, size.height - h - px(0.4, texel_m))), w, h);
    const int border = px(rng.uniform(0.01, 0.03), texel_m);
    cv::rectangle(img, r, random_color(rng, 10, 120), cv::FILLED);
    const cv::Rect inner(r.x + border, r.y + border, std::max(1, w - 2 * border),
                         std::max(1, h - 2 * border));
    if (rng.uniform() < 0.5) {
      abstract_art(img, inner, rng);
    } else {
      cv::rectangle(img, inner, random_color(rng, 200, 250), cv::FILLED);
      text_block(img, inner, std::max(4, px(0.012, texel_m)), rng, random_color(rng, 0, 90));
    }
  }
  const int notes = std::max(3, static_cast<int>(area_m2 / 1.2));
  for (int i = 0; i < notes; ++i) {
    const int s = px(rng.uniform(0.06, 0.1), texel_m);
    const cv::Point p(rng.uniform_int(0, std::max(0, size.width - s)),
                      rng.uniform_int(0, std::max(0, size.height - s)));
    const cv::Rect r(p, cv::Size(s, s));
    cv::rectangle(img, r, cv::Scalar(rng.uniform(60, 160), rng.uniform(200, 255), 250), cv::FILLED);
    text_block(img, cv::Rect(p.x + 2, p.y, s - 4, s), std::max(3, s / 7), rng,
               cv::Scalar(120, 40, 20));
  }
  // Baseboard (the bottom rows meet the floor).
  const int board = px(0.09, texel_m);
  cv::rectangle(img, cv::Rect(0, size.height - board, size.width, board), shifted(base, -110),
                cv::FILLED);
  cv::line(img, cv::Point(0, size.height - board), cv::Point(size.width, size.height - board),
           cv::Scalar(30, 30, 30), 2);
  return img;
}

cv::Mat make_floor_texture(cv::Size size, double texel_m, Rng& rng) {
  cv::Mat img(size, CV_8UC3, cv::Scalar(40, 70, 110));
  const cv::Scalar wood(rng.uniform(40, 80), rng.uniform(90, 130), rng.uniform(140, 190));
  // Grain: noise stretched along the planks (x).
  cv::Mat grain_small = fractal_noise(cv::Size(std::max(2, size.width / 60), size.height), rng,
                                      px(0.05, texel_m), 1, 0.7);
  cv::Mat grain;
  cv::resize(grain_small, grain, size, 0, 0, cv::INTER_LINEAR);
  int y = 0;
  while (y < size.height) {
    const int h = px(rng.uniform(0.09, 0.2), texel_m);
    int x = -rng.uniform_int(0, px(1.0, texel_m));
    while (x < size.width) {
      const int w = px(rng.uniform(0.5, 1.5), texel_m);
      const cv::Rect r = cv::Rect(x, y, w, h) & cv::Rect(0, 0, size.width, size.height);
      if (r.area() > 0) {
        img(r).setTo(shifted(wood, rng.uniform(-35, 35)));
        for (int k = rng.uniform_int(0, 2); k > 0; --k) {
          const cv::Point c(r.x + rng.uniform_int(0, r.width), r.y + rng.uniform_int(0, r.height));
          cv::ellipse(img, c, cv::Size(px(0.02, texel_m), px(0.008, texel_m)), 0, 0, 360,
                      shifted(wood, -70), cv::FILLED, cv::LINE_AA);
        }
      }
      cv::line(img, cv::Point(x, y), cv::Point(x, y + h), cv::Scalar(20, 30, 45), 2);
      x += w;
    }
    cv::line(img, cv::Point(0, y), cv::Point(size.width, y), cv::Scalar(20, 30, 45), 2);
    y += h;
  }
  add_noise(img, grain, 40.0);
  add_noise(img, fractal_noise(size, rng, px(0.6, texel_m), 2, 0.6), 14.0);
  // Scuffs, knots and spots: dense enough for corners everywhere on the floor.
  const double area_m2 = size.area() * texel_m * texel_m;
  for (int i = 0; i < static_cast<int>(area_m2 * 160); ++i) {
    const cv::Point p(rng.uniform_int(0, size.width - 1), rng.uniform_int(0, size.height - 1));
    const double delta = rng.uniform() < 0.6 ? rng.uniform(-110, -50) : rng.uniform(50, 90);
    motif(img, p, px(rng.uniform(0.01, 0.05), texel_m), shifted(wood, delta), rng);
  }
  // A rug with a random geometric pattern.
  const int rw = px(rng.uniform(1.2, 2.0), texel_m);
  const int rh = px(rng.uniform(0.8, 1.4), texel_m);
  const cv::Rect rug(rng.uniform_int(0, std::max(0, size.width - rw)),
                     rng.uniform_int(0, std::max(0, size.height - rh)), rw, rh);
  const cv::Rect rug_in = rug & cv::Rect(0, 0, size.width, size.height);
  abstract_art(img, rug_in, rng);
  // Woven texture and a dense small pattern, so the rug's large shapes are not flat.
  cv::Mat rug_img = img(rug_in);
  add_noise(rug_img, fractal_noise(rug_in.size(), rng, px(0.2, texel_m), 1, 0.8), 30.0);
  const int rug_motifs = static_cast<int>(rug_in.area() * texel_m * texel_m / (0.05 * 0.05));
  for (int i = 0; i < rug_motifs; ++i) {
    const cv::Point p(rug_in.x + rng.uniform_int(0, rug_in.width - 1),
                      rug_in.y + rng.uniform_int(0, rug_in.height - 1));
    motif(img, p, px(rng.uniform(0.01, 0.04), texel_m),
          rng.uniform() < 0.5 ? cv::Scalar::all(rng.uniform(0, 60)) : vivid_color(rng), rng);
  }
  cv::rectangle(img, rug, vivid_color(rng), px(0.04, texel_m));
  return img;
}

cv::Mat make_ceiling_texture(cv::Size size, double texel_m, Rng& rng) {
  cv::Mat img(size, CV_8UC3, cv::Scalar(215, 220, 222));
  const int tile = px(0.6, texel_m);
  const cv::Point offset(rng.uniform_int(0, tile), rng.uniform_int(0, tile));
  for (int ty = -1; ty * tile < size.height; ++ty) {
    for (int tx = -1; tx * tile < size.width; ++tx) {
      const cv::Rect r(offset.x + tx * tile, offset.y + ty * tile, tile, tile);
      if (rng.uniform() < 0.12) {
        cv::rectangle(img, r, cv::Scalar(250, 252, 252), cv::FILLED);  // light panel
        cv::rectangle(img, r, cv::Scalar(150, 150, 150), px(0.03, texel_m));
        continue;
      }
      const cv::Rect inside = r & cv::Rect(0, 0, size.width, size.height);
      const double darken = rng.uniform(0, 25);
      if (inside.area() > 0) {
        cv::Mat roi = img(inside);
        roi -= cv::Scalar::all(darken);
      }
      // Perforations and marks: dense enough for corners at every pyramid level.
      for (int k = 0; k < 70; ++k) {
        const cv::Point p(r.x + rng.uniform_int(0, tile), r.y + rng.uniform_int(0, tile));
        cv::circle(img, p, px(rng.uniform(0.003, 0.014), texel_m),
                   cv::Scalar::all(rng.uniform(60, 150)), cv::FILLED, cv::LINE_AA);
      }
      if (rng.uniform() < 0.3) {  // a stain, a vent or a smoke detector
        const cv::Point p(r.x + rng.uniform_int(tile / 5, tile * 4 / 5),
                          r.y + rng.uniform_int(tile / 5, tile * 4 / 5));
        motif(img, p, px(rng.uniform(0.05, 0.2), texel_m), random_color(rng, 60, 170), rng);
      }
    }
  }
  for (int x = offset.x % tile; x < size.width; x += tile)
    cv::line(img, {x, 0}, {x, size.height}, cv::Scalar(120, 120, 125), 3);
  for (int y = offset.y % tile; y < size.height; y += tile)
    cv::line(img, {0, y}, {size.width, y}, cv::Scalar(120, 120, 125), 3);
  add_noise(img, fractal_noise(size, rng, px(1.0, texel_m), 2, 0.6), 24.0);
  return img;
}

cv::Mat make_wood_texture(cv::Size size, double texel_m, Rng& rng, bool clutter) {
  const cv::Scalar wood(rng.uniform(60, 120), rng.uniform(100, 150), rng.uniform(140, 200));
  cv::Mat img(size, CV_8UC3, wood);
  cv::Mat grain_small = fractal_noise(cv::Size(std::max(2, size.width / 40), size.height), rng,
                                      px(0.03, texel_m), 1, 0.7);
  cv::Mat grain;
  cv::resize(grain_small, grain, size, 0, 0, cv::INTER_LINEAR);
  add_noise(img, grain, 42.0);
  add_noise(img, fractal_noise(size, rng, px(0.3, texel_m), 2, 0.6), 16.0);
  const double area_m2 = size.area() * texel_m * texel_m;
  for (int i = 0; i < static_cast<int>(area_m2 * 220) + 2; ++i) {
    const cv::Point p(rng.uniform_int(0, size.width - 1), rng.uniform_int(0, size.height - 1));
    const double delta = rng.uniform() < 0.6 ? rng.uniform(-120, -55) : rng.uniform(55, 100);
    motif(img, p, px(rng.uniform(0.01, 0.045), texel_m), shifted(wood, delta), rng);
  }
  if (!clutter) {
    // Panel edges and handles.
    const int n = std::max(1, static_cast<int>(size.width * texel_m / 0.45));
    for (int i = 1; i < n; ++i) {
      const int x = i * size.width / n + rng.uniform_int(-5, 5);
      cv::line(img, {x, 0}, {x, size.height}, shifted(wood, -80), 2);
      const cv::Rect handle(x - px(0.05, texel_m), size.height / 5, px(0.02, texel_m),
                            px(0.1, texel_m));
      cv::rectangle(img, handle, cv::Scalar(180, 180, 185), cv::FILLED);
      cv::rectangle(img, handle, cv::Scalar(60, 60, 60), 1);
    }
    return img;
  }
  const int papers = std::max(2, static_cast<int>(area_m2 / 0.12));
  for (int i = 0; i < papers; ++i) {
    const cv::Point2f c(rng.uniform(0, size.width), rng.uniform(0, size.height));
    const cv::Size2f s(px(0.21, texel_m), px(0.297, texel_m));
    const double angle = rng.uniform(-40, 40);
    cv::Mat sheet(cv::Size(static_cast<int>(s.width), static_cast<int>(s.height)), CV_8UC3,
                  cv::Scalar::all(rng.uniform(225, 250)));
    text_block(sheet, cv::Rect(6, 6, sheet.cols - 12, sheet.rows - 12),
               std::max(4, px(0.009, texel_m)), rng, cv::Scalar(40, 30, 30));
    if (rng.uniform() < 0.5)
      abstract_art(sheet, cv::Rect(10, sheet.rows / 2, sheet.cols / 2, sheet.rows / 4), rng);
    const cv::Mat rot =
        cv::getRotationMatrix2D(cv::Point2f(sheet.cols / 2.f, sheet.rows / 2.f), angle, 1.0);
    cv::Mat rot_shift = rot.clone();
    rot_shift.at<double>(0, 2) += c.x - sheet.cols / 2.0;
    rot_shift.at<double>(1, 2) += c.y - sheet.rows / 2.0;
    cv::warpAffine(sheet, img, rot_shift, img.size(), cv::INTER_LINEAR, cv::BORDER_TRANSPARENT);
  }
  for (int i = 0; i < papers; ++i) {  // pens and mug rings
    const cv::Point p(rng.uniform_int(0, size.width - 1), rng.uniform_int(0, size.height - 1));
    const double a = rng.uniform(0, kPi);
    const int l = px(0.14, texel_m);
    cv::line(img, p,
             p + cv::Point(static_cast<int>(l * std::cos(a)), static_cast<int>(l * std::sin(a))),
             vivid_color(rng), px(0.008, texel_m), cv::LINE_AA);
    cv::circle(img, {rng.uniform_int(0, size.width - 1), rng.uniform_int(0, size.height - 1)},
               px(0.04, texel_m), shifted(wood, -60), px(0.005, texel_m), cv::LINE_AA);
  }
  // A keyboard: a dark slab with keys of varying widths (a short repeat, broken by labels).
  const cv::Rect kb(rng.uniform_int(0, std::max(0, size.width - px(0.45, texel_m))),
                    rng.uniform_int(0, std::max(0, size.height - px(0.15, texel_m))),
                    px(0.45, texel_m), px(0.15, texel_m));
  cv::rectangle(img, kb, cv::Scalar(35, 35, 38), cv::FILLED);
  const int key = px(0.018, texel_m);
  for (int ky = kb.y + 4; ky + key < kb.y + kb.height; ky += key + 3) {
    for (int kx = kb.x + 4 + rng.uniform_int(0, key / 2); kx + key < kb.x + kb.width;) {
      const int w = rng.uniform() < 0.15 ? key * 2 : key;
      cv::rectangle(img, cv::Rect(kx, ky, w, key), cv::Scalar::all(rng.uniform(60, 110)),
                    cv::FILLED);
      put_text(img, std::string(1, static_cast<char>('A' + rng.uniform_int(0, 25))),
               {kx + 2, ky + key - 3}, key * 0.5, cv::FONT_HERSHEY_PLAIN, cv::Scalar::all(230));
      kx += w + 3;
    }
  }
  return img;
}

cv::Mat make_bookshelf_texture(cv::Size size, double texel_m, Rng& rng) {
  const cv::Scalar wood(rng.uniform(40, 90), rng.uniform(70, 120), rng.uniform(110, 170));
  cv::Mat img(size, CV_8UC3, shifted(wood, -70));
  const int board = px(0.025, texel_m);
  int y = 0;
  while (y < size.height) {
    const int row_h = px(rng.uniform(0.3, 0.4), texel_m);
    cv::rectangle(img, cv::Rect(0, y, size.width, board), wood, cv::FILLED);
    const int bottom = std::min(size.height, y + row_h);
    int x = rng.uniform_int(0, px(0.05, texel_m));
    while (x < size.width) {
      if (rng.uniform() < 0.06) {  // a gap or a leaning stack
        x += px(rng.uniform(0.04, 0.15), texel_m);
        continue;
      }
      const int w = px(rng.uniform(0.015, 0.055), texel_m);
      const int h = std::min(bottom - y - board - 2, px(rng.uniform(0.17, 0.31), texel_m));
      if (h <= 4 || x + w > size.width) break;
      const cv::Rect spine(x, bottom - h, w, h);
      const cv::Scalar c = rng.uniform() < 0.6 ? vivid_color(rng) : random_color(rng, 20, 230);
      cv::rectangle(img, spine, c, cv::FILLED);
      cv::rectangle(img, spine, shifted(c, -80), 1);
      for (int b = rng.uniform_int(0, 3); b > 0; --b) {
        const int by = spine.y + rng.uniform_int(0, spine.height - 3);
        cv::rectangle(img, cv::Rect(spine.x, by, w, std::max(2, px(0.006, texel_m))),
                      shifted(c, rng.uniform() < 0.5 ? -90 : 90), cv::FILLED);
      }
      // Title: written along the spine (text drawn horizontally, then rotated).
      if (w > 8 && h > 30) {
        cv::Mat label(cv::Size(h - 8, w - 4), CV_8UC3, c);
        put_text(label, random_line(rng, rng.uniform_int(1, 3)), {2, label.rows - 3},
                 std::max(4.0, label.rows * 0.55), random_font(rng),
                 rng.uniform() < 0.5 ? cv::Scalar::all(245) : cv::Scalar::all(15));
        cv::rotate(label, label, cv::ROTATE_90_CLOCKWISE);
        label.copyTo(img(cv::Rect(spine.x + 2, spine.y + 4, label.cols, label.rows)));
      }
      x += w + rng.uniform_int(0, 2);
    }
    y = bottom;
  }
  add_noise(img, fractal_noise(size, rng, px(0.4, texel_m), 2, 0.6), 8.0);
  return img;
}

cv::Mat make_cardboard_texture(cv::Size size, double texel_m, Rng& rng) {
  const cv::Scalar brown(rng.uniform(70, 100), rng.uniform(130, 160), rng.uniform(170, 205));
  cv::Mat img(size, CV_8UC3, brown);
  add_noise(img, fractal_noise(size, rng, px(0.1, texel_m), 1, 0.7), 16.0);
  const int tape = px(0.05, texel_m);
  cv::rectangle(img, cv::Rect(0, size.height / 2 - tape / 2, size.width, tape), shifted(brown, 35),
                cv::FILLED);
  const int lw = std::max(8, size.width * 2 / 5);
  const int lh = std::max(8, size.height / 3);
  const cv::Rect label(rng.uniform_int(2, std::max(2, size.width - lw - 2)),
                       rng.uniform_int(2, std::max(2, size.height - lh - 2)), lw, lh);
  cv::rectangle(img, label, cv::Scalar::all(240), cv::FILLED);
  text_block(img, cv::Rect(label.x + 3, label.y, label.width - 6, label.height / 2),
             std::max(4, px(0.01, texel_m)), rng, cv::Scalar(20, 20, 20));
  for (int x = label.x + 4; x < label.x + label.width - 4;) {  // barcode
    const int w = rng.uniform_int(1, 4);
    if (rng.uniform() < 0.55) {
      cv::rectangle(img, cv::Rect(x, label.y + label.height * 2 / 3, w, label.height / 4),
                    cv::Scalar::all(10), cv::FILLED);
    }
    x += w;
  }
  for (int i = 0; i < 3; ++i) {
    const cv::Point p(rng.uniform_int(0, size.width - 1), rng.uniform_int(0, size.height - 1));
    const int s = px(rng.uniform(0.03, 0.08), texel_m);
    cv::arrowedLine(img, p, p + cv::Point(0, -s), cv::Scalar(30, 30, 30), std::max(1, s / 8),
                    cv::LINE_AA, 0, 0.35);
    put_text(img, random_word(rng, 3, 7, true), p + cv::Point(s / 3, 0), s * 0.4,
             cv::FONT_HERSHEY_SIMPLEX, cv::Scalar(30, 30, 160));
  }
  return img;
}

cv::Mat make_poster_texture(cv::Size size, Rng& rng) {
  cv::Mat img(size, CV_8UC3, random_color(rng, 20, 240));
  const cv::Scalar top = random_color(rng, 20, 240);
  for (int y = 0; y < size.height; ++y) {
    const double w = static_cast<double>(y) / size.height;
    img.row(y) = img.row(y) * (1.0 - 0.6 * (1 - w)) + top * 0.6 * (1 - w);
  }
  abstract_art(
      img, cv::Rect(size.width / 10, size.height / 6, size.width * 8 / 10, size.height / 2), rng);
  for (int i = 0; i < 12; ++i) {
    motif(img, {rng.uniform_int(0, size.width), rng.uniform_int(0, size.height)},
          static_cast<int>(size.width * rng.uniform(0.04, 0.2)), vivid_color(rng), rng);
  }
  const cv::Scalar ink = cv::Scalar::all(rng.uniform() < 0.5 ? 15 : 245);
  put_text(img, random_word(rng, 4, 9, true), {size.width / 12, size.height / 8},
           size.height * 0.06, random_font(rng), ink);
  text_block(img,
             cv::Rect(size.width / 12, size.height * 7 / 10, size.width * 5 / 6, size.height / 4),
             std::max(5.0, size.height * 0.022), rng, ink);
  return img;
}

void make_person_silhouette(cv::Size size, Rng& rng, cv::Mat& bgr, cv::Mat& alpha) {
  alpha = cv::Mat(size, CV_8UC1, cv::Scalar(0));
  bgr = cv::Mat(size, CV_8UC3, cv::Scalar(128, 128, 128));
  const double w = size.width;
  const double h = size.height;
  const cv::Scalar skin(rng.uniform(60, 150), rng.uniform(100, 170), rng.uniform(150, 225));
  const cv::Scalar shirt = vivid_color(rng);
  const cv::Scalar trousers = random_color(rng, 20, 120);
  auto part = [&](auto draw, const cv::Scalar& color) {
    draw(bgr, color);
    draw(alpha, cv::Scalar(255));
  };
  const cv::Point head(static_cast<int>(w / 2), static_cast<int>(h * 0.07));
  part(
      [&](cv::Mat& m, const cv::Scalar& c) {
        cv::ellipse(m, head, cv::Size(static_cast<int>(w * 0.13), static_cast<int>(h * 0.065)), 0,
                    0, 360, c, cv::FILLED, cv::LINE_8);
      },
      skin);
  const std::vector<cv::Point> torso = {{static_cast<int>(w * 0.25), static_cast<int>(h * 0.15)},
                                        {static_cast<int>(w * 0.75), static_cast<int>(h * 0.15)},
                                        {static_cast<int>(w * 0.70), static_cast<int>(h * 0.52)},
                                        {static_cast<int>(w * 0.30), static_cast<int>(h * 0.52)}};
  part([&](cv::Mat& m, const cv::Scalar& c) { cv::fillConvexPoly(m, torso, c, cv::LINE_8); },
       shirt);
  const int limb = static_cast<int>(w * 0.1);
  part(
      [&](cv::Mat& m, const cv::Scalar& c) {
        cv::line(m, {static_cast<int>(w * 0.27), static_cast<int>(h * 0.17)},
                 {static_cast<int>(w * 0.12), static_cast<int>(h * 0.5)}, c, limb, cv::LINE_8);
        cv::line(m, {static_cast<int>(w * 0.73), static_cast<int>(h * 0.17)},
                 {static_cast<int>(w * 0.88), static_cast<int>(h * 0.5)}, c, limb, cv::LINE_8);
      },
      shirt);
  part(
      [&](cv::Mat& m, const cv::Scalar& c) {
        cv::line(m, {static_cast<int>(w * 0.4), static_cast<int>(h * 0.5)},
                 {static_cast<int>(w * 0.36), static_cast<int>(h * 0.96)}, c, limb + 4, cv::LINE_8);
        cv::line(m, {static_cast<int>(w * 0.6), static_cast<int>(h * 0.5)},
                 {static_cast<int>(w * 0.64), static_cast<int>(h * 0.96)}, c, limb + 4, cv::LINE_8);
      },
      trousers);
  // Printed shirt and fabric noise so the silhouette carries features like a photo would.
  cv::Mat print = bgr.clone();
  abstract_art(print,
               cv::Rect(static_cast<int>(w * 0.32), static_cast<int>(h * 0.2),
                        static_cast<int>(w * 0.36), static_cast<int>(h * 0.18)),
               rng);
  print.copyTo(bgr, alpha);
  add_noise(bgr, fractal_noise(size, rng, w / 4, 1, 0.7), 20.0);
}

}  // namespace ddl::synthetic
