#include "ddl/eval/dense_eval.h"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>
#include <deque>
#include <filesystem>
#include <iterator>
#include <map>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <set>

#include "ddl/core/error.h"
#include "ddl/core/filesystem.h"
#include "ddl/eval/ate.h"
#include "ddl/io/trajectory_io.h"
#include "ddl/io/tum_dataset.h"

namespace ddl::eval {
namespace fs = std::filesystem;

void DenseEvalOptions::validate() const {
  auto fail = [](const char* key, const char* what) {
    throw ConfigError::for_key(std::string("eval_dense.") + key, what);
  };
  if (previous_keyframes < 1) fail("previous_keyframes", "must be >= 1");
  if (frame_stride < 1) fail("frame_stride", "must be >= 1");
  if (pixel_stride < 1) fail("pixel_stride", "must be >= 1");
  if (!(radius_voxels > 0.0 && radius_voxels <= 10.0)) fail("radius_voxels", "must be in (0, 10]");
  if (!(max_difference_s > 0.0)) fail("max_difference_s", "must be > 0");
  if (!(seen.depth_tolerance_m >= 0.0 && seen.depth_tolerance_rel >= 0.0)) {
    fail("seen.depth_tolerance_m", "tolerances must be >= 0");
  }
}

namespace {

/// Everything of the sequence the evaluation reads, by frame index.
class TruthSequence {
 public:
  TruthSequence(const std::string& dir, const camera::PinholeCamera& camera,
                double max_difference_s)
      : dir_(dir),
        frames_(dir, camera),
        background_(require_dir(dir, "background"), camera),
        undistorter_(camera),
        max_difference_s_(max_difference_s) {
    require_dir(dir, "dynamic_mask");
    const fs::path gt = fs::path(dir) / "groundtruth.txt";
    groundtruth_ = io::read_tum_trajectory(gt.string());
    groundtruth_path_ = gt.string();
    for (std::size_t i = 0; i < frames_.size(); ++i) stamps_.push_back(frames_.timestamp(i));
    for (std::size_t i = 0; i < background_.size(); ++i) {
      background_index_.push_back(index_near(background_.timestamp(i), stamps_));
    }
  }

  std::size_t size() const { return frames_.size(); }
  double stamp(std::size_t i) const { return stamps_[i]; }
  const camera::PinholeCamera& camera() const { return frames_.camera(); }
  const io::Trajectory& groundtruth() const { return groundtruth_; }
  const std::string& groundtruth_path() const { return groundtruth_path_; }

  /// Index of the frame at `stamp_s`; nullopt when none is within max_difference_s.
  std::optional<std::size_t> frame_at(double stamp_s) const {
    const std::size_t i = index_near(stamp_s, stamps_);
    if (i >= stamps_.size() || std::abs(stamps_[i] - stamp_s) >= max_difference_s_) {
      return std::nullopt;
    }
    return i;
  }

  io::RgbdFrame frame(std::size_t i) const { return frames_.frame(i); }

  io::RgbdFrame background(std::size_t i) const {
    const auto it = std::find(background_index_.begin(), background_index_.end(), i);
    if (it == background_index_.end()) {
      throw InputError::at((fs::path(dir_) / "background").string(),
                           fmt::format("no background frame at {:.6f}", stamps_[i]));
    }
    return background_.frame(static_cast<std::size_t>(it - background_index_.begin()));
  }

  cv::Mat dynamic_mask(std::size_t i) const {
    const fs::path path =
        fs::path(dir_) / "dynamic_mask" / fs::path(frames_.pairs()[i].rgb_path).filename();
    cv::Mat mask = cv::imread(path.string(), cv::IMREAD_GRAYSCALE);
    if (mask.empty()) throw InputError::at(path.string(), "missing or unreadable dynamic mask");
    return undistorter_.undistort_depth(mask);
  }

  /// True T_w_c at frame i (the nearest ground-truth pose within max_difference_s).
  SE3 pose(std::size_t i) const {
    const double t = stamps_[i];
    const auto it =
        std::lower_bound(groundtruth_.begin(), groundtruth_.end(), t,
                         [](const io::StampedPose& p, double s) { return p.timestamp_s < s; });
    const io::StampedPose* best = nullptr;
    if (it != groundtruth_.end()) best = &*it;
    if (it != groundtruth_.begin() &&
        (best == nullptr || t - std::prev(it)->timestamp_s < best->timestamp_s - t)) {
      best = &*std::prev(it);
    }
    if (best == nullptr || std::abs(best->timestamp_s - t) >= max_difference_s_) {
      throw InputError::at(groundtruth_path_, fmt::format("no pose within {} s of frame {:.6f}",
                                                          max_difference_s_, t));
    }
    return best->T_w_c();
  }

 private:
  static std::string require_dir(const std::string& dir, const char* sub) {
    const fs::path p = fs::path(dir) / sub;
    if (!fs::is_directory(p)) {
      throw InputError::at(p.string(),
                           "missing: eval-dense needs a synthetic sequence (`ddl_slam synth`)");
    }
    return p.string();
  }

  static std::size_t index_near(double t, const std::vector<double>& stamps) {
    const auto it = std::lower_bound(stamps.begin(), stamps.end(), t);
    std::size_t i = static_cast<std::size_t>(it - stamps.begin());
    if (i > 0 && (i == stamps.size() || t - stamps[i - 1] < stamps[i] - t)) --i;
    return i;
  }

  std::string dir_;
  io::TumDataset frames_;
  io::TumDataset background_;
  camera::Undistorter undistorter_;
  double max_difference_s_;
  io::Trajectory groundtruth_;
  std::string groundtruth_path_;
  std::vector<double> stamps_;
  std::vector<std::size_t> background_index_;  // background frame -> sequence frame
};

cv::Mat read_image(const std::string& path, int flags) {
  cv::Mat image = cv::imread(path, flags);
  if (image.empty()) throw InputError::at(path, "missing or unreadable image");
  return image;
}

struct RepairedKeyframe {
  cv::Mat bgr, depth_m, mask, unfilled;
};

RepairedKeyframe read_repaired(const std::string& stem_path, double depth_factor) {
  RepairedKeyframe r;
  r.bgr = read_image(stem_path + "_rgb.png", cv::IMREAD_COLOR);
  const cv::Mat depth_raw = read_image(stem_path + "_depth.png", cv::IMREAD_UNCHANGED);
  if (depth_raw.type() != CV_16UC1) {
    throw InputError::at(stem_path + "_depth.png", "expected a 16-bit depth image");
  }
  depth_raw.convertTo(r.depth_m, CV_32FC1, 1.0 / depth_factor);
  r.mask = read_image(stem_path + "_mask.png", cv::IMREAD_GRAYSCALE);
  r.unfilled = read_image(stem_path + "_unfilled.png", cv::IMREAD_GRAYSCALE);
  return r;
}

/// The repaired keyframes of a run, in stamp order: (stamp, <dir>/<stem>).
std::vector<std::pair<double, std::string>> list_repaired(const fs::path& dir) {
  std::vector<std::pair<double, std::string>> out;
  if (!fs::is_directory(dir)) return out;
  const std::string suffix = "_rgb.png";
  for (const auto& entry : fs::directory_iterator(dir)) {
    const std::string name = entry.path().filename().string();
    if (name.size() <= suffix.size() ||
        name.compare(name.size() - suffix.size(), suffix.size(), suffix) != 0) {
      continue;
    }
    const std::string stem = name.substr(0, name.size() - suffix.size());
    // The whole stem must be a finite number: std::stod alone takes "12.5x" as 12.5 and "nan",
    // which then matched frame 0.
    double stamp = 0.0;
    std::size_t used = 0;
    try {
      stamp = std::stod(stem, &used);
    } catch (const std::exception&) {
      used = 0;
    }
    if (used != stem.size() || !std::isfinite(stamp)) {
      throw InputError::at(entry.path().string(), "repaired keyframe name is not <stamp>_rgb.png");
    }
    out.emplace_back(stamp, (dir / stem).string());
  }
  std::sort(out.begin(), out.end());
  return out;
}

void evaluate_inpainting(const TruthSequence& truth, const DenseEvalOptions& options,
                         const fs::path& inpainted_dir, DenseEvalResult& result) {
  const auto repaired = list_repaired(inpainted_dir);
  std::deque<TrueView> previous;  // newest last
  for (const auto& [stamp, stem_path] : repaired) {
    const auto index = truth.frame_at(stamp);
    if (!index) {
      throw InputError::at(stem_path + "_rgb.png", fmt::format("stamp {:.6f} is no frame of {}",
                                                               stamp, result.inputs.sequence_dir));
    }
    const io::RgbdFrame frame = truth.frame(*index);
    const io::RgbdFrame background = truth.background(*index);
    const RepairedKeyframe rep = read_repaired(stem_path, truth.camera().depth_factor);
    const cv::Mat dynamic = truth.dynamic_mask(*index);
    const SE3 T_w_c = truth.pose(*index);

    InpaintingFrameInputs in;
    in.repaired_bgr = rep.bgr;
    in.repaired_depth_m = rep.depth_m;
    in.repair_mask = rep.mask;
    in.unfilled = rep.unfilled;
    in.original_bgr = frame.rgb;
    in.original_depth_m = frame.depth_m;
    in.dynamic_mask = dynamic;
    in.background_bgr = background.rgb;
    in.background_depth_m = background.depth_m;
    const std::vector<TrueView> earlier(previous.begin(), previous.end());
    in.seen =
        seen_background(dynamic, background.depth_m, T_w_c, earlier, truth.camera(), options.seen);
    KeyframeEvaluation k;
    k.frame_index = *index;
    k.stem = stem_path;
    try {
      k.metrics = evaluate_inpainted_frame(in);
    } catch (const std::invalid_argument& e) {  // sizes or types that differ from the sequence's
      throw InputError::at(stem_path + "_*.png", e.what());
    }
    k.metrics.timestamp_s = stamp;
    result.total += k.metrics;
    result.keyframes.push_back(std::move(k));

    previous.push_back({T_w_c, frame.depth_m, dynamic});
    if (previous.size() > options.previous_keyframes) previous.pop_front();
  }
}

MapEvaluation evaluate_map(const TruthSequence& truth, const DenseEvalOptions& options,
                           const DenseEvalInputs& inputs,
                           const std::vector<KeyframeEvaluation>& keyframes) {
  const MapVoxels& voxels = *inputs.map;
  if (!(voxels.resolution_m > 0.0)) throw InputError::at(voxels.path, "map without a resolution");
  MapEvaluation m;
  m.path = voxels.path;
  m.resolution_m = voxels.resolution_m;
  m.radius_m = options.radius_voxels * voxels.resolution_m;

  // The estimate's world -> ground-truth world, exactly as ATE aligns the run's trajectory.
  const fs::path estimate_path = fs::path(inputs.run_dir) / "CameraTrajectory.txt";
  const io::Trajectory estimate = io::read_tum_trajectory(estimate_path.string());
  AteOptions ate_options;
  ate_options.max_difference_s = options.max_difference_s;
  const AteResult ate = compute_ate(truth.groundtruth(), estimate, ate_options);
  m.alignment_rmse_m = ate.stats_m.rmse;
  m.alignment_pairs = ate.errors_m.size();
  Alignment alignment = ate.alignment;
  if (options.align_with_orientations) {
    // The same associated pairs, aligned as whole poses (orientations included).
    std::map<double, SE3> gt_by_stamp;
    for (const io::StampedPose& p : truth.groundtruth())
      gt_by_stamp.emplace(p.timestamp_s, p.T_w_c());
    std::map<double, SE3> est_by_stamp;
    for (const io::StampedPose& p : estimate) est_by_stamp.emplace(p.timestamp_s, p.T_w_c());
    std::vector<SE3> gt_poses;
    std::vector<SE3> est_poses;
    for (std::size_t i = 0; i < ate.stamps_gt_s.size(); ++i) {
      const auto g = gt_by_stamp.find(ate.stamps_gt_s[i]);
      const auto e = est_by_stamp.find(ate.stamps_est_s[i]);
      if (g == gt_by_stamp.end() || e == est_by_stamp.end()) continue;
      gt_poses.push_back(g->second);
      est_poses.push_back(e->second);
    }
    alignment = align_poses(gt_poses, est_poses);
  }

  // Reference clouds over the frames the run processed: every frame_stride-th frame of the
  // estimate's time span, and every repaired keyframe (whose dynamic content could have been
  // mapped).
  std::set<std::size_t> frames;
  const double begin_s = estimate.front().timestamp_s - options.max_difference_s;
  const double end_s = estimate.back().timestamp_s + options.max_difference_s;
  std::size_t counter = 0;
  for (std::size_t i = 0; i < truth.size(); ++i) {
    if (truth.stamp(i) < begin_s || truth.stamp(i) > end_s) continue;
    if (counter++ % options.frame_stride == 0) frames.insert(i);
  }
  for (const KeyframeEvaluation& k : keyframes) frames.insert(k.frame_index);

  const double merge_m = m.radius_m / 10.0;
  PointGrid static_points(m.radius_m, merge_m);
  PointGrid dynamic_points(m.radius_m, merge_m);
  const camera::PinholeCamera& cam = truth.camera();
  const int stride = options.pixel_stride;
  for (const std::size_t i : frames) {
    const SE3 T_w_c = truth.pose(i);
    const io::RgbdFrame frame = truth.frame(i);
    const io::RgbdFrame background = truth.background(i);
    const cv::Mat dynamic = truth.dynamic_mask(i);
    for (int v = 0; v < frame.depth_m.rows; v += stride) {
      const float* bg = background.depth_m.ptr<float>(v);
      const float* d = frame.depth_m.ptr<float>(v);
      const std::uint8_t* dyn = dynamic.ptr(v);
      for (int u = 0; u < frame.depth_m.cols; u += stride) {
        if (bg[u] > 0.0f) static_points.insert(T_w_c * cam.unproject(u, v, bg[u]));
        if (dyn[u] != 0 && d[u] > 0.0f) dynamic_points.insert(T_w_c * cam.unproject(u, v, d[u]));
      }
    }
  }
  m.reference_frames = frames.size();
  m.static_points = static_points.size();
  m.dynamic_points = dynamic_points.size();

  std::vector<Vec3d> centres_gt;
  centres_gt.reserve(voxels.centres.size());
  for (const Vec3d& c : voxels.centres) centres_gt.push_back(alignment.apply(c));
  m.voxels = classify_voxels(centres_gt, static_points, dynamic_points, m.radius_m, &m.labels);
  m.centres_gt = std::move(centres_gt);
  return m;
}

double ratio(std::uint64_t a, std::uint64_t b) {
  return b > 0 ? static_cast<double>(a) / static_cast<double>(b)
               : std::numeric_limits<double>::quiet_NaN();
}

/// JSON number or null (NaN, inf).
nlohmann::json number(double x) { return std::isfinite(x) ? nlohmann::json(x) : nullptr; }

}  // namespace

DenseEvalResult evaluate_dense(const DenseEvalInputs& inputs, const DenseEvalOptions& options) {
  options.validate();
  const TruthSequence truth(inputs.sequence_dir, inputs.camera, options.max_difference_s);
  DenseEvalResult result;
  result.inputs = inputs;
  result.inputs.map.reset();
  result.options = options;
  evaluate_inpainting(truth, options, fs::path(inputs.run_dir) / "inpainted", result);
  spdlog::info("inpainting: {} repaired keyframes evaluated", result.keyframes.size());
  if (inputs.map) {
    result.map = evaluate_map(truth, options, inputs, result.keyframes);
    spdlog::info("map: {} occupied voxels against {} static / {} dynamic reference points",
                 result.map->voxels.occupied, result.map->static_points,
                 result.map->dynamic_points);
  }
  return result;
}

std::string format_dense_report(const DenseEvalResult& r) {
  std::string out;
  const InpaintingFrameMetrics& t = r.total;
  if (r.keyframes.empty()) {
    out += "inpainting: no repaired keyframes (run with --save-inpainted)\n";
  } else {
    out += fmt::format(
        "inpainting over {} keyframes (previous {} keyframes for 'seen'):\n"
        "  true dynamic pixels      {}\n"
        "  seen by earlier keyframes {} ({:.1f}%)\n"
        "  filled                   {:.1f}% of dynamic, {:.1f}% of seen\n"
        "  PSNR over filled pixels  {:.2f} dB repaired, {:.2f} dB unfilled (original frame)\n"
        "  PSNR over dynamic pixels {:.2f} dB repaired, {:.2f} dB unfilled\n"
        "  median |depth error|     {:.4f} m filled ({} px), {:.4f} m unfilled\n",
        r.keyframes.size(), r.options.previous_keyframes, t.dynamic_px, t.seen_px,
        100.0 * ratio(t.seen_px, t.dynamic_px), 100.0 * ratio(t.filled_px, t.dynamic_px),
        100.0 * ratio(t.filled_seen_px, t.seen_px), t.filled_rgb.psnr_db(),
        t.filled_rgb_original.psnr_db(), t.dynamic_rgb.psnr_db(), t.dynamic_rgb_original.psnr_db(),
        t.filled_depth.median_m(), t.filled_depth.abs_m.size(), t.filled_depth_original.median_m());
  }
  if (r.map) {
    const MapEvaluation& m = *r.map;
    const VoxelClasses& v = m.voxels;
    out += fmt::format(
        "map {} ({:.3f} m voxels, near = {:.3f} m; aligned by {} over {} poses, ATE RMSE "
        "{:.4f} m):\n"
        "  occupied voxels          {}\n"
        "  near static geometry     {} ({:.2f}%)\n"
        "  ghost (only dynamic)     {} ({:.2f}%)\n"
        "  other                    {} ({:.2f}%)\n",
        m.path, m.resolution_m, m.radius_m,
        r.options.align_with_orientations ? "whole poses" : "positions (as ATE)", m.alignment_pairs,
        m.alignment_rmse_m, v.occupied, v.true_static, 100.0 * v.fraction(v.true_static), v.ghost,
        100.0 * v.fraction(v.ghost), v.other, 100.0 * v.fraction(v.other));
  }
  return out;
}

nlohmann::json to_json(const DenseEvalResult& r) {
  nlohmann::json j;
  j["inputs"] = {{"sequence", r.inputs.sequence_dir}, {"run", r.inputs.run_dir}};
  j["options"] = {{"previous_keyframes", r.options.previous_keyframes},
                  {"seen_depth_tolerance_m", r.options.seen.depth_tolerance_m},
                  {"seen_depth_tolerance_rel", r.options.seen.depth_tolerance_rel},
                  {"frame_stride", r.options.frame_stride},
                  {"pixel_stride", r.options.pixel_stride},
                  {"radius_voxels", r.options.radius_voxels}};
  const InpaintingFrameMetrics& t = r.total;
  nlohmann::json in;
  in["keyframes"] = r.keyframes.size();
  in["dynamic_px"] = t.dynamic_px;
  in["seen_px"] = t.seen_px;
  in["filled_px"] = t.filled_px;
  in["filled_seen_px"] = t.filled_seen_px;
  in["filled_fraction_of_dynamic"] = number(ratio(t.filled_px, t.dynamic_px));
  in["filled_fraction_of_seen"] = number(ratio(t.filled_seen_px, t.seen_px));
  in["psnr_filled_db"] = number(t.filled_rgb.psnr_db());
  in["psnr_filled_unfilled_baseline_db"] = number(t.filled_rgb_original.psnr_db());
  in["psnr_dynamic_db"] = number(t.dynamic_rgb.psnr_db());
  in["psnr_dynamic_unfilled_baseline_db"] = number(t.dynamic_rgb_original.psnr_db());
  in["depth_median_abs_filled_m"] = number(t.filled_depth.median_m());
  in["depth_median_abs_filled_unfilled_baseline_m"] = number(t.filled_depth_original.median_m());
  in["depth_compared_px"] = t.filled_depth.abs_m.size();
  in["depth_missing_px"] = t.filled_depth.missing;
  nlohmann::json per = nlohmann::json::array();
  for (const KeyframeEvaluation& k : r.keyframes) {
    const InpaintingFrameMetrics& m = k.metrics;
    per.push_back({{"stamp", fmt::format("{:.6f}", m.timestamp_s)},
                   {"dynamic_px", m.dynamic_px},
                   {"seen_px", m.seen_px},
                   {"filled_px", m.filled_px},
                   {"filled_seen_px", m.filled_seen_px},
                   {"repair_mask_px", m.repair_mask_px},
                   {"psnr_filled_db", number(m.filled_rgb.psnr_db())},
                   {"psnr_filled_unfilled_baseline_db", number(m.filled_rgb_original.psnr_db())},
                   {"depth_median_abs_filled_m", number(m.filled_depth.median_m())}});
  }
  in["per_keyframe"] = per;
  j["inpainting"] = in;
  if (r.map) {
    const MapEvaluation& m = *r.map;
    const VoxelClasses& v = m.voxels;
    j["map"] = {{"file", m.path},
                {"resolution_m", m.resolution_m},
                {"radius_m", m.radius_m},
                {"occupied", v.occupied},
                {"true_static", v.true_static},
                {"ghost", v.ghost},
                {"other", v.other},
                {"true_static_fraction", number(v.fraction(v.true_static))},
                {"ghost_fraction", number(v.fraction(v.ghost))},
                {"other_fraction", number(v.fraction(v.other))},
                {"reference_frames", m.reference_frames},
                {"static_points", m.static_points},
                {"dynamic_points", m.dynamic_points},
                {"alignment", r.options.align_with_orientations ? "poses" : "positions"},
                {"alignment_ate_rmse_m", m.alignment_rmse_m},
                {"alignment_pairs", m.alignment_pairs}};
  }
  return j;
}

cv::Mat inpainting_montage(const DenseEvalResult& result, int rows, int tile_width) {
  if (result.keyframes.empty() || rows < 1) return {};
  const TruthSequence truth(result.inputs.sequence_dir, result.inputs.camera,
                            result.options.max_difference_s);
  // The keyframe with the most dynamic pixels in each of `rows` equal parts of the run.
  std::vector<const KeyframeEvaluation*> picks;
  const std::size_t n = result.keyframes.size();
  const std::size_t parts = std::min<std::size_t>(static_cast<std::size_t>(rows), n);
  for (std::size_t p = 0; p < parts; ++p) {
    const KeyframeEvaluation* best = nullptr;
    for (std::size_t i = p * n / parts; i < (p + 1) * n / parts; ++i) {
      if (best == nullptr || result.keyframes[i].metrics.dynamic_px > best->metrics.dynamic_px) {
        best = &result.keyframes[i];
      }
    }
    picks.push_back(best);
  }
  const cv::Size image = truth.camera().width > 0
                             ? cv::Size(truth.camera().width, truth.camera().height)
                             : cv::Size(640, 480);
  const int tile_height = tile_width * image.height / image.width;
  const int header = 22;
  cv::Mat montage(header + tile_height * static_cast<int>(picks.size()), 3 * tile_width, CV_8UC3,
                  cv::Scalar(255, 255, 255));
  const char* titles[] = {"original (true dynamic outline)", "repaired (magenta: unfilled)",
                          "true background"};
  for (int c = 0; c < 3; ++c) {
    cv::putText(montage, titles[c], {c * tile_width + 4, 15}, cv::FONT_HERSHEY_SIMPLEX, 0.38,
                cv::Scalar(30, 30, 30), 1, cv::LINE_AA);
  }
  for (std::size_t r = 0; r < picks.size(); ++r) {
    const KeyframeEvaluation& k = *picks[r];
    const io::RgbdFrame frame = truth.frame(k.frame_index);
    const io::RgbdFrame background = truth.background(k.frame_index);
    const cv::Mat dynamic = truth.dynamic_mask(k.frame_index);
    const RepairedKeyframe rep = read_repaired(k.stem, truth.camera().depth_factor);
    cv::Mat original = frame.rgb.clone();
    std::vector<std::vector<cv::Point>> contours;
    cv::findContours(dynamic.clone(), contours, cv::RETR_EXTERNAL, cv::CHAIN_APPROX_SIMPLE);
    cv::drawContours(original, contours, -1, cv::Scalar(0, 0, 255), 3);
    cv::Mat repaired = rep.bgr.clone();
    repaired.setTo(cv::Scalar(255, 0, 255), rep.unfilled);
    const cv::Mat tiles[] = {original, repaired, background.rgb};
    for (int c = 0; c < 3; ++c) {
      cv::Mat small;
      cv::resize(tiles[c], small, {tile_width, tile_height}, 0, 0, cv::INTER_AREA);
      small.copyTo(montage(cv::Rect(c * tile_width, header + static_cast<int>(r) * tile_height,
                                    tile_width, tile_height)));
    }
    cv::putText(montage,
                fmt::format("{:.3f}  filled {:.0f}%  PSNR {:.1f} dB", k.metrics.timestamp_s,
                            100.0 * ratio(k.metrics.filled_px, k.metrics.dynamic_px),
                            k.metrics.filled_rgb.psnr_db()),
                {tile_width + 4, header + static_cast<int>(r + 1) * tile_height - 6},
                cv::FONT_HERSHEY_SIMPLEX, 0.35, cv::Scalar(255, 255, 255), 1, cv::LINE_AA);
  }
  return montage;
}

void write_classified_voxels_ply(const MapEvaluation& map, const std::string& path) {
  std::string text = fmt::format(
      "ply\nformat ascii 1.0\ncomment DDL-SLAM eval-dense: near static green, ghost red, "
      "other blue; ground-truth frame\nelement vertex {}\nproperty float x\nproperty "
      "float y\nproperty float z\nproperty uchar red\nproperty uchar green\nproperty "
      "uchar blue\nend_header\n",
      map.centres_gt.size());
  for (std::size_t i = 0; i < map.centres_gt.size(); ++i) {
    const Vec3d& p = map.centres_gt[i];
    const VoxelClass c = i < map.labels.size() ? map.labels[i] : VoxelClass::kOther;
    const char* rgb = c == VoxelClass::kStatic  ? "0 200 0"
                      : c == VoxelClass::kGhost ? "220 0 0"
                                                : "0 0 220";
    fmt::format_to(std::back_inserter(text), "{:.4f} {:.4f} {:.4f} {}\n", p.x(), p.y(), p.z(), rgb);
  }
  write_file_atomically(path, "the classified voxels", text);
}

}  // namespace ddl::eval
