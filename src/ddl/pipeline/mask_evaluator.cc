#include "ddl/pipeline/mask_evaluator.h"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "ddl/core/error.h"
#include "ddl/core/filesystem.h"
#include "ddl/io/text_table.h"

namespace ddl::pipeline {
namespace fs = std::filesystem;
namespace {

constexpr double kStampTolerance_s = 5e-4;  // stamps are written with 6 decimals

/// Index of the entry of `sorted` (by .first or .stamp_s) nearest to `stamp_s` within the
/// tolerance, or -1.
template <typename T, typename Key>
std::ptrdiff_t find_stamp(const std::vector<T>& sorted, double stamp_s, Key key) {
  const auto it = std::lower_bound(sorted.begin(), sorted.end(), stamp_s,
                                   [&](const T& e, double s) { return key(e) < s; });
  std::ptrdiff_t best = -1;
  double best_d = kStampTolerance_s;
  for (auto c : {it, it == sorted.begin() ? it : std::prev(it)}) {
    if (c == sorted.end()) continue;
    const double d = std::abs(key(*c) - stamp_s);
    if (d <= best_d) {
      best_d = d;
      best = c - sorted.begin();
    }
  }
  return best;
}

Vec3d vec3(const nlohmann::json& j, const std::string& path, const std::string& key) {
  if (!j.is_array() || j.size() != 3) {
    throw InputError::at(path, "\"" + key + "\" must be an array of 3 numbers");
  }
  return {j[0].get<double>(), j[1].get<double>(), j[2].get<double>()};
}

/// The rows of a mask list ("timestamp filename", '#' comments), sorted by stamp.
std::vector<std::pair<double, std::string>> read_mask_list(const fs::path& list) {
  std::vector<std::pair<double, std::string>> rows;
  for (const io::TextRow& row : io::read_text_table(list.string())) {
    if (row.fields.size() != 2) {
      throw InputError::at_line(list.string(), row.line, "expected 'timestamp filename'");
    }
    rows.emplace_back(io::parse_double(row.fields[0], list.string(), row.line), row.fields[1]);
  }
  std::sort(rows.begin(), rows.end());
  return rows;
}

/// The file of `list` at `stamp_s`, or nullptr.
const std::string* mask_file(const std::vector<std::pair<double, std::string>>& list,
                             double stamp_s) {
  const std::ptrdiff_t i = find_stamp(list, stamp_s, [](const auto& e) { return e.first; });
  return i < 0 ? nullptr : &list[static_cast<std::size_t>(i)].second;
}

}  // namespace

std::optional<MovedObjectRegion> MovedObjectRegion::load(const std::string& sequence_dir,
                                                         const camera::PinholeCamera& camera,
                                                         int grow_px) {
  const fs::path meta_path = fs::path(sequence_dir) / "meta.json";
  const fs::path gt_path = fs::path(sequence_dir) / "groundtruth.txt";
  if (!fs::exists(meta_path) || !fs::exists(gt_path)) return std::nullopt;
  nlohmann::json meta;
  {
    std::ifstream file(meta_path);
    try {
      meta = nlohmann::json::parse(file);
    } catch (const nlohmann::json::exception& e) {
      throw InputError::at(meta_path.string(), std::string("not valid JSON: ") + e.what());
    }
  }
  if (!meta.contains("scene") || !meta["scene"].contains("object")) return std::nullopt;
  const std::string path = meta_path.string();
  MovedObjectRegion r;
  r.camera_ = camera;
  r.grow_px_ = grow_px;
  try {
    const nlohmann::json& object = meta["scene"]["object"];
    const int entity = object.at("entity").get<int>();
    r.size_m_ = vec3(object.at("size_m"), path, "scene.object.size_m");
    r.from_w_ = vec3(object.at("from_bottom_centre_w"), path, "scene.object.from_bottom_centre_w");
    r.to_w_ = vec3(object.at("to_bottom_centre_w"), path, "scene.object.to_bottom_centre_w");
    r.yaw_from_ = object.at("yaw_from_rad").get<double>();
    r.yaw_to_ = object.at("yaw_to_rad").get<double>();
    for (const nlohmann::json& f : meta.at("frames")) {
      for (const nlohmann::json& e : f.at("entities")) {
        if (e.at("entity").get<int>() != entity) continue;
        FrameState s;
        s.stamp_s = std::stod(f.at("rgb_stamp").get<std::string>());
        s.dynamic = e.at("dynamic").get<bool>();
        s.centre_w = vec3(e.at("position_w"), path, "frames[].entities[].position_w");
        r.frames_.push_back(s);
      }
    }
  } catch (const nlohmann::json::exception& e) {
    throw InputError::at(path, std::string("unexpected layout of the moved object: ") + e.what());
  } catch (const std::logic_error& e) {  // std::stod
    throw InputError::at(path, std::string("bad rgb_stamp: ") + e.what());
  }
  std::sort(r.frames_.begin(), r.frames_.end(),
            [](const FrameState& a, const FrameState& b) { return a.stamp_s < b.stamp_s; });
  r.groundtruth_ = io::read_tum_trajectory(gt_path.string());
  return r;
}

cv::Mat MovedObjectRegion::region(double stamp_s) const {
  const std::ptrdiff_t i =
      find_stamp(frames_, stamp_s, [](const FrameState& f) { return f.stamp_s; });
  if (i < 0 || !frames_[static_cast<std::size_t>(i)].dynamic) return {};
  const std::ptrdiff_t g =
      find_stamp(groundtruth_, stamp_s, [](const io::StampedPose& p) { return p.timestamp_s; });
  if (g < 0) return {};
  const FrameState& f = frames_[static_cast<std::size_t>(i)];
  // The carry's progress along its path gives the yaw (both interpolate with the same s).
  const Vec2d path = (to_w_ - from_w_).head<2>();
  const Vec3d bottom_w = f.centre_w - Vec3d(0, 0, size_m_.z() / 2);
  const double s =
      path.squaredNorm() > 1e-12
          ? std::clamp((bottom_w - from_w_).head<2>().dot(path) / path.squaredNorm(), 0.0, 1.0)
          : 1.0;
  const double yaw = yaw_from_ + s * (yaw_to_ - yaw_from_);
  const Vec3d ax(std::cos(yaw), std::sin(yaw), 0.0);
  const Vec3d ay(-std::sin(yaw), std::cos(yaw), 0.0);
  const SE3 T_c_w = groundtruth_[static_cast<std::size_t>(g)].T_w_c().inverse();
  std::vector<cv::Point> corners;
  for (int k = 0; k < 8; ++k) {
    const Vec3d p_w = bottom_w + ((k & 1) ? 0.5 : -0.5) * size_m_.x() * ax +
                      ((k & 2) ? 0.5 : -0.5) * size_m_.y() * ay +
                      Vec3d(0, 0, (k & 4) ? size_m_.z() : 0.0);
    const Vec3d p_c = T_c_w * p_w;
    if (p_c.z() < 0.05) return {};
    const Vec2d uv = camera_.project(p_c);
    corners.emplace_back(static_cast<int>(std::lround(uv.x())),
                         static_cast<int>(std::lround(uv.y())));
  }
  std::vector<cv::Point> hull;
  cv::convexHull(corners, hull);
  cv::Mat mask = cv::Mat::zeros(camera_.height, camera_.width, CV_8UC1);
  cv::fillConvexPoly(mask, hull, cv::Scalar(255));
  if (grow_px_ > 0) {
    cv::dilate(
        mask, mask,
        cv::getStructuringElement(cv::MORPH_ELLIPSE, cv::Size(2 * grow_px_ + 1, 2 * grow_px_ + 1)));
  }
  return mask;
}

MaskEvaluator::MaskEvaluator(std::string sequence_dir, const camera::PinholeCamera& stored_camera)
    : sequence_dir_(std::move(sequence_dir)), undistorter_(stored_camera) {}

std::unique_ptr<MaskEvaluator> MaskEvaluator::open(const std::string& sequence_dir,
                                                   const camera::PinholeCamera& stored_camera) {
  const fs::path list = fs::path(sequence_dir) / "dynamic_mask.txt";
  if (!fs::exists(list)) return nullptr;
  std::unique_ptr<MaskEvaluator> e(new MaskEvaluator(sequence_dir, stored_camera));
  e->truth_ = read_mask_list(list);
  const fs::path void_list = fs::path(sequence_dir) / "void_mask.txt";
  if (fs::exists(void_list)) e->void_ = read_mask_list(void_list);
  // The box region is drawn with the undistorted camera (synthetic rooms have no distortion).
  e->moved_object_ = MovedObjectRegion::load(sequence_dir, stored_camera.undistorted());
  spdlog::info("mask evaluation against {} ({} masks{}{})", list.string(), e->truth_.size(),
               e->void_.empty() ? "" : fmt::format(", {} void masks", e->void_.size()),
               e->moved_object_ ? ", moved object from meta.json" : "");
  return e;
}

cv::Mat MaskEvaluator::read_mask(const std::string& file) const {
  const fs::path path = fs::path(sequence_dir_) / file;
  const cv::Mat mask = cv::imread(path.string(), cv::IMREAD_GRAYSCALE);
  if (mask.empty()) throw InputError::at(path.string(), "cannot read the mask");
  return undistorter_.undistort_depth(mask);
}

void MaskEvaluator::add(const io::RgbdFrame& frame, const DynamicMasks& masks) {
  const std::string* file = mask_file(truth_, frame.timestamp_s);
  if (file == nullptr) {
    ++frames_without_truth_;
    return;
  }
  const cv::Mat truth = read_mask(*file);
  // Scored pixels: all but the void ones (none without a void list).
  cv::Mat scored;
  if (!void_.empty()) {
    const std::string* void_file = mask_file(void_, frame.timestamp_s);
    if (void_file == nullptr) {
      throw InputError::at((fs::path(sequence_dir_) / "void_mask.txt").string(),
                           fmt::format("no void mask for the frame at {:.6f}, which has a "
                                       "ground-truth mask",
                                       frame.timestamp_s));
    }
    const cv::Mat void_mask = read_mask(*void_file);
    if (void_mask.size() != truth.size()) {
      throw InputError::at((fs::path(sequence_dir_) / *void_file).string(),
                           "size differs from the ground-truth mask's");
    }
    void_pixels_ += static_cast<std::uint64_t>(cv::countNonZero(void_mask));
    cv::compare(void_mask, 0, scored, cv::CMP_EQ);
  }
  FrameCounts& counts = frames_.emplace_back();
  counts.stamp_s = frame.timestamp_s;
  counts.cnn = eval::count_mask_pixels(masks.cnn, truth, scored);
  counts.geometry = eval::count_mask_pixels(masks.geometry, truth, scored);
  counts.free_space = eval::count_mask_pixels(masks.free_space, truth, scored);
  counts.combined = eval::count_mask_pixels(masks.combined, truth, scored);
  cnn_.add(counts.cnn);
  geometry_.add(counts.geometry);
  free_space_.add(counts.free_space);
  combined_.add(counts.combined);
  if (!moved_object_) return;
  cv::Mat region = moved_object_->region(frame.timestamp_s);
  if (region.empty() || region.size() != truth.size()) return;
  cv::bitwise_and(region, truth, region);
  if (cv::countNonZero(region) == 0) return;
  ++object_frames_;
  object_cnn_ += eval::count_mask_pixels(masks.cnn, truth, region);
  object_geometry_ += eval::count_mask_pixels(masks.geometry, truth, region);
  object_free_space_ += eval::count_mask_pixels(masks.free_space, truth, region);
  object_combined_ += eval::count_mask_pixels(masks.combined, truth, region);
}

eval::MaskSummary MaskEvaluator::summary(const std::string& source) const {
  if (source == "cnn") return cnn_.summary();
  if (source == "geometry") return geometry_.summary();
  if (source == "free_space") return free_space_.summary();
  if (source == "combined") return combined_.summary();
  throw std::invalid_argument("MaskEvaluator::summary: unknown source " + source);
}

void MaskEvaluator::write_frames_csv(const std::string& path) const {
  std::string text =
      "# per-frame mask pixel counts against the ground truth (void pixels excluded)\n"
      "stamp,truth_px,cnn_tp,cnn_fp,cnn_fn,geometry_tp,geometry_fp,geometry_fn,"
      "free_space_tp,free_space_fp,free_space_fn,combined_tp,combined_fp,combined_fn\n";
  for (const FrameCounts& f : frames_) {
    text += fmt::format("{:.6f},{}", f.stamp_s, f.combined.truth_pixels());
    for (const eval::MaskCounts* c : {&f.cnn, &f.geometry, &f.free_space, &f.combined}) {
      text += fmt::format(",{},{},{}", c->true_positive, c->false_positive, c->false_negative);
    }
    text += '\n';
  }
  write_file_atomically(path, "the per-frame mask scores", text);
}

nlohmann::json MaskEvaluator::to_json() const {
  nlohmann::json j = {
      {"truth", (fs::path(sequence_dir_) / "dynamic_mask.txt").string()},
      {"frames_without_truth", frames_without_truth_},
      {"void", void_.empty()
                   ? nlohmann::json(nullptr)
                   : nlohmann::json{{"list", (fs::path(sequence_dir_) / "void_mask.txt").string()},
                                    {"px", void_pixels_}}},
      {"cnn", eval::to_json(cnn_.summary())},
      {"geometry", eval::to_json(geometry_.summary())},
      {"free_space", eval::to_json(free_space_.summary())},
      {"combined", eval::to_json(combined_.summary())}};
  if (moved_object_) {
    auto recall = [](const eval::MaskCounts& c) {
      return c.truth_pixels() > 0 ? nlohmann::json(static_cast<double>(c.true_positive) /
                                                   static_cast<double>(c.truth_pixels()))
                                  : nlohmann::json(nullptr);
    };
    j["moved_object"] = {{"frames", object_frames_},
                         {"truth_px", object_combined_.truth_pixels()},
                         {"recall",
                          {{"cnn", recall(object_cnn_)},
                           {"geometry", recall(object_geometry_)},
                           {"free_space", recall(object_free_space_)},
                           {"combined", recall(object_combined_)}}},
                         {"region", fmt::format("convex hull of the box's projected corners "
                                                "(meta.json, groundtruth.txt) grown by {} px, "
                                                "intersected with the truth",
                                                moved_object_->grow_px())}};
  }
  return j;
}

}  // namespace ddl::pipeline
