// Generated sequences: ground-truth conventions, determinism, TUM layout.

#include "ddl/synthetic/sequence.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <optional>
#include <set>

#include "ddl/core/error.h"
#include "ddl/io/text_table.h"
#include "ddl/io/trajectory_io.h"
#include "ddl/io/tum_dataset.h"
#include "test_support.h"

#ifdef DDL_HAVE_SEGMENTATION
#include "config_error_check.h"
#include "ddl/segmentation/segmenter.h"
#endif

namespace ddl::synthetic {
namespace {

namespace fs = std::filesystem;
using testing::small_config;
using testing::TempDir;

/// Pixels where two images differ (any channel), CV_8UC1 255.
cv::Mat differs(const cv::Mat& a, const cv::Mat& b) {
  cv::Mat diff;
  cv::absdiff(a, b, diff);
  if (diff.channels() > 1) {
    cv::Mat gray;
    cv::transform(diff, gray, cv::Matx13f(1, 1, 1));
    diff = gray;
  }
  return diff > 0;
}

int count_outside(const cv::Mat& pixels, const cv::Mat& allowed) {
  cv::Mat outside;
  cv::bitwise_and(pixels, ~allowed, outside);
  return cv::countNonZero(outside);
}

/// The composite preset on the shared fr1_rpy, with the shared photos of people when
/// `with_photos`; nullopt when fr1_rpy is not there (`skip_reason` says where it was looked for).
std::optional<SequenceConfig> fr1_composite(bool with_photos, std::string& skip_reason) {
  const std::string background = testing::shared_dir() + "/data/tum/rgbd_dataset_freiburg1_rpy";
  if (!fs::exists(background + "/groundtruth.txt")) {
    skip_reason = "TUM fr1_rpy not found at " + background + " (set DDL_SHARED_DIR)";
    return std::nullopt;
  }
  SequenceConfig config = find_preset("composite_fr1_rpy_walking").config;
  config.background_dir = background;
  if (with_photos) config.people_dir = testing::shared_dir() + "/data/people/ccp";
  return config;
}

TEST(Sequence, DynamicMaskIsExactlyTheRenderedPeople) {
  const auto source = make_sequence_source(small_config("syn_walking_xyz", 300));
  double max_fraction = 0.0;
  int frames_with_people = 0;
  for (std::size_t i = 0; i < 300; i += 20) {
    const FrameData f = source->render_frame(i);
    max_fraction = std::max(max_fraction, f.dynamic_fraction);
    // The frame and its background differ only inside the mask (same noise elsewhere).
    EXPECT_EQ(count_outside(differs(f.rgb, f.background_rgb), f.dynamic_mask), 0) << i;
    // Depth differs at most in the mask grown by the 2 px edge dropouts.
    cv::Mat grown;
    cv::dilate(f.dynamic_mask, grown, cv::Mat::ones(5, 5, CV_8U));
    EXPECT_EQ(count_outside(differs(f.depth_raw, f.background_depth_raw), grown), 0) << i;
    // Mask pixels are exactly the pixels whose visible entity is a person.
    const cv::Mat people = f.entity >= 1;
    EXPECT_EQ(cv::norm(people, f.dynamic_mask, cv::NORM_INF), 0.0) << i;
    // And a person is in front of what the background shows there.
    for (int v = 0; v < f.entity.rows; ++v) {
      for (int u = 0; u < f.entity.cols; ++u) {
        if (f.dynamic_mask.at<unsigned char>(v, u) == 0) continue;
        ASSERT_LT(f.depth_exact_m.at<float>(v, u), f.background_depth_exact_m.at<float>(v, u));
      }
    }
    if (f.dynamic_fraction > 0.01) ++frames_with_people;
  }
  EXPECT_GT(max_fraction, 0.15) << "people should at times cover a large part of the image";
  EXPECT_LT(max_fraction, 0.75);
  EXPECT_GE(frames_with_people, 10) << "two walkers are in view most of the time";
}

TEST(Sequence, MovedObjectBecomesDynamicWhenItMoves) {
  // syn_sitting_static: two seated people (entities 1, 2) and a box (entity 3) moved at 12 s.
  const auto source = make_sequence_source(small_config("syn_sitting_static", 707));
  const FrameData before = source->render_frame(300);  // 10 s
  const FrameData during = source->render_frame(375);  // 12.5 s
  const FrameData after = source->render_frame(450);   // 15 s
  const cv::Mat box_before = before.entity == 3;
  ASSERT_GT(cv::countNonZero(box_before), 50) << "the box should be in view";
  EXPECT_EQ(cv::countNonZero(box_before & before.dynamic_mask), 0);
  EXPECT_FALSE(before.entities[2].dynamic);
  for (const FrameData* f : {&during, &after}) {
    const cv::Mat box = f->entity == 3;
    ASSERT_GT(cv::countNonZero(box), 50);
    EXPECT_EQ(count_outside(box, f->dynamic_mask), 0);
    EXPECT_TRUE(f->entities[2].dynamic);
    EXPECT_EQ(count_outside(differs(f->rgb, f->background_rgb), f->dynamic_mask), 0);
  }
  // The box ends elsewhere: its pixels after the move are not where they were before.
  const cv::Mat box_after = after.entity == 3;
  EXPECT_LT(cv::countNonZero(box_after & box_before), cv::countNonZero(box_before) / 2);
  // Seated people are dynamic and in the mask in every frame.
  EXPECT_GT(cv::countNonZero(before.dynamic_mask & (before.entity == 1)), 100);
}

std::vector<std::string> list_files(const fs::path& root) {
  std::vector<std::string> out;
  for (const auto& e : fs::recursive_directory_iterator(root)) {
    if (e.is_regular_file()) out.push_back(fs::relative(e.path(), root).string());
  }
  std::sort(out.begin(), out.end());
  return out;
}

std::string read_bytes(const fs::path& p) {
  std::ifstream f(p, std::ios::binary);
  return {std::istreambuf_iterator<char>(f), std::istreambuf_iterator<char>()};
}

class WrittenSequence : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_a_ = new TempDir("ddl_synth_a");
    dir_b_ = new TempDir("ddl_synth_b");
    const SequenceConfig config = small_config("syn_walking_xyz", 4);
    write_sequence(*make_sequence_source(config), dir_a_->str());
    write_sequence(*make_sequence_source(config), dir_b_->str());
  }
  static void TearDownTestSuite() {
    delete dir_a_;
    delete dir_b_;
  }
  static TempDir* dir_a_;
  static TempDir* dir_b_;
};
TempDir* WrittenSequence::dir_a_ = nullptr;
TempDir* WrittenSequence::dir_b_ = nullptr;

TEST_F(WrittenSequence, SameSeedGivesTheSameBytes) {
  const auto files = list_files(dir_a_->path());
  ASSERT_EQ(files, list_files(dir_b_->path()));
  // 5 image folders x 4 frames + 11 index/meta files (accelerometer.txt included).
  EXPECT_EQ(files.size(), 5u * 4u + 11u);
  for (const auto& f : files) {
    EXPECT_EQ(read_bytes(dir_a_->path() / f), read_bytes(dir_b_->path() / f)) << f;
  }
  // Another seed gives other images.
  SequenceConfig other = small_config("syn_walking_xyz", 1);
  other.seed += 1;
  const FrameData f = make_sequence_source(other)->render_frame(0);
  const cv::Mat first = cv::imread((dir_a_->path() / "rgb/1341840000.000000.png").string());
  EXPECT_GT(cv::norm(first, f.rgb, cv::NORM_L1), 0.0);
}

TEST_F(WrittenSequence, TumReaderReadsIt) {
  const camera::PinholeCamera cam = small_config("syn_walking_xyz", 4).camera;
  const io::TumDataset dataset(dir_a_->str(), cam);
  ASSERT_EQ(dataset.size(), 4u);
  EXPECT_EQ(dataset.association_description(), "associations.txt");
  for (std::size_t i = 0; i < dataset.size(); ++i) {
    const auto frame = dataset.frame(i);
    EXPECT_EQ(frame.rgb.type(), CV_8UC3);
    EXPECT_EQ(frame.depth_m.type(), CV_32FC1);
    EXPECT_EQ(frame.rgb.size(), cv::Size(320, 240));
    EXPECT_GT(cv::countNonZero(frame.depth_m), 320 * 240 / 2);
    EXPECT_NEAR(frame.timestamp_s, 1341840000.0 + static_cast<double>(i) / 30.0, 1e-6);
    // Depth stamps differ from RGB stamps by a few ms, like a Kinect's.
    const auto& pair = dataset.pairs()[i];
    EXPECT_LE(std::abs(pair.depth_timestamp_s - pair.rgb_timestamp_s), 0.0061);
  }
  ASSERT_TRUE(dataset.groundtruth_path().has_value());
  const auto gt = io::read_tum_trajectory(*dataset.groundtruth_path());
  ASSERT_EQ(gt.size(), 4u);
  EXPECT_DOUBLE_EQ(gt[1].timestamp_s, dataset.timestamp(1));
  // The accelerometer gives each frame the ground truth's up (world z) within a few degrees: the
  // camera's own acceleration and the sensor noise are all that separate them (measured: 4.4
  // degrees at most in these four frames, 8.4 over the whole of syn_walking_xyz).
  io::SequenceOptions with_accelerometer;
  with_accelerometer.read_accelerometer = true;
  const io::TumDataset accelerometer_dataset(dir_a_->str(), cam, with_accelerometer);
  ASSERT_TRUE(accelerometer_dataset.accelerometer().has_value());
  for (std::size_t i = 0; i < accelerometer_dataset.size(); ++i) {
    const auto up_c = accelerometer_dataset.frame(i).up_c;
    ASSERT_TRUE(up_c.has_value()) << i;
    const Vec3d truth_up_c = gt[i].T_w_c().rotation().transpose() * Vec3d::UnitZ();
    EXPECT_GT(up_c->dot(truth_up_c), std::cos(10.0 * M_PI / 180.0)) << i;
  }
  // The three-line TUM headers and the extra lists.
  const std::string rgb_txt = read_bytes(dir_a_->path() / "rgb.txt");
  EXPECT_EQ(rgb_txt.rfind("# color images\n# file: '", 0), 0u);
  EXPECT_EQ(io::read_text_table((dir_a_->path() / "dynamic_mask.txt").string()).size(), 4u);
  const io::TumDataset background((dir_a_->path() / "background").string(), cam);
  EXPECT_EQ(background.size(), 4u);
  const std::string yaml = read_bytes(dir_a_->path() / "camera.yaml");
  for (const char* key : {"camera:\n", "  name: ", "  fx: 267.7\n", "  distortion: [0, 0, 0, 0, 0]",
                          "  depth_factor: 5000\n", "  fps: 30\n"}) {
    EXPECT_NE(yaml.find(key), std::string::npos) << key;
  }
  const std::string meta = read_bytes(dir_a_->path() / "meta.json");
  EXPECT_NE(meta.find("\"dynamic_fraction\""), std::string::npos);
}

TEST(Sequence, GroundTruthPosesAndDepthAgreeAcrossFrames) {
  // Through the written files only: a point unprojected from frame 0's depth with frame 0's
  // ground-truth pose, projected into frame 24 with its pose, lands where frame 24 sees the
  // same depth.
  TempDir dir("ddl_synth_gt");
  SequenceConfig config = small_config("syn_static_xyz", 25);
  config.depth.enabled = false;
  config.rgb_noise_sigma = 0;
  write_sequence(*make_sequence_source(config), dir.str());
  const io::TumDataset dataset(dir.str(), config.camera);
  const auto gt = io::read_tum_trajectory(*dataset.groundtruth_path());
  ASSERT_EQ(gt.size(), 25u);
  const auto f0 = dataset.frame(0);
  const auto f1 = dataset.frame(24);
  const SE3 T_w_0 = gt[0].T_w_c();
  const SE3 T_1_w = gt[24].T_w_c().inverse();
  ASSERT_GT((gt[24].t_w_c - gt[0].t_w_c).norm(), 0.05) << "needs a baseline";
  std::vector<double> errors;
  const auto& cam = config.camera;
  for (int v = 2; v < cam.height - 2; v += 4) {
    for (int u = 2; u < cam.width - 2; u += 4) {
      const float d = f0.depth_m.at<float>(v, u);
      if (d <= 0) continue;
      const Vec3d p1 = T_1_w * (T_w_0 * cam.unproject(u, v, d));
      const Vec2d uv = cam.project(p1);
      if (!cam.in_image(uv, 2)) continue;
      const int u0 = static_cast<int>(uv.x());
      const int v0 = static_cast<int>(uv.y());
      const float a = f1.depth_m.at<float>(v0, u0), b = f1.depth_m.at<float>(v0, u0 + 1);
      const float c = f1.depth_m.at<float>(v0 + 1, u0), e = f1.depth_m.at<float>(v0 + 1, u0 + 1);
      if (std::max({a, b, c, e}) - std::min({a, b, c, e}) > 0.02 || std::min({a, b, c, e}) <= 0) {
        continue;  // a depth edge: occlusion or silhouette
      }
      const double wx = uv.x() - u0, wy = uv.y() - v0;
      const double z = (1 - wy) * ((1 - wx) * a + wx * b) + wy * ((1 - wx) * c + wx * e);
      errors.push_back(std::abs(z - p1.z()));
    }
  }
  ASSERT_GT(errors.size(), 2000u);
  std::sort(errors.begin(), errors.end());
  EXPECT_LT(errors[errors.size() / 2], 0.001);
  EXPECT_LT(errors[errors.size() * 95 / 100], 0.005);
}

TEST(Sequence, CompositeDrawsPeopleOnlyInFrontOfTheRealScene) {
  std::string skip;
  std::optional<SequenceConfig> found = fr1_composite(true, skip);
  if (!found) GTEST_SKIP() << skip;
  SequenceConfig config = *found;
  ASSERT_TRUE(config.background_camera.depth_time_offset_s.has_value());  // tum1's
  const auto source = make_sequence_source(config);
  EXPECT_GT(source->frame_count(), 600u);
  int frames_with_people = 0;
  int frames_checked = 0;
  for (std::size_t i = 0; i < source->frame_count(); i += 50, ++frames_checked) {
    const FrameData f = source->render_frame(i);
    EXPECT_EQ(count_outside(differs(f.rgb, f.background_rgb), f.dynamic_mask), 0);
    // The depth holds the people as the sensor saw them at its own instant.
    cv::Mat grown;
    cv::dilate(f.depth_dynamic_mask, grown, cv::Mat::ones(3, 3, CV_8U));
    EXPECT_EQ(count_outside(differs(f.depth_raw, f.background_depth_raw), grown), 0);
    // Nearer than the real surface; where the sensor measured nothing, nearer than the nearest
    // measured pixel (a person does not show through the holes of a monitor's depth).
    const cv::Mat surface = fill_missing_depth_nearest(f.background_depth_exact_m);
    for (int v = 0; v < f.rgb.rows; ++v) {
      for (int u = 0; u < f.rgb.cols; ++u) {
        if (f.depth_dynamic_mask.at<unsigned char>(v, u) == 0) continue;
        ASSERT_LT(f.depth_exact_m.at<float>(v, u), surface.at<float>(v, u)) << u << "," << v;
      }
    }
    if (f.dynamic_fraction > 0.02) ++frames_with_people;
  }
  // Over the whole sequence people cover > 2% of the image in about 80% of the frames (the
  // camera rotates away from them at times).
  EXPECT_GE(frames_with_people, frames_checked / 2);
}

// tum1's depth was captured about 20 ms before its stamp: on fr1_rpy's fast turns the people in
// the depth image sit several pixels off those in the colour image, as the real scene does.
// Without the offset the two silhouettes are one.
TEST(Sequence, CompositeDrawsThePeopleIntoTheDepthAtTheDepthsInstant) {
  std::string skip;
  std::optional<SequenceConfig> found = fr1_composite(true, skip);
  if (!found) GTEST_SKIP() << skip;
  SequenceConfig config = *found;
  config.frames = 420;
  const auto offset_source = make_sequence_source(config);
  config.background_camera.depth_time_offset_s.reset();
  const auto synchronised_source = make_sequence_source(config);
  const auto iou = [](const cv::Mat& a, const cv::Mat& b) {
    return static_cast<double>(cv::countNonZero(a & b)) / std::max(1, cv::countNonZero(a | b));
  };
  int frames = 0, shifted = 0;
  for (std::size_t i = 300; i < 420; i += 10) {
    const FrameData f = offset_source->render_frame(i);
    const FrameData g = synchronised_source->render_frame(i);
    EXPECT_EQ(cv::countNonZero(differs(f.rgb, g.rgb)), 0) << "frame " << i;  // the same colour
    if (cv::countNonZero(g.dynamic_mask) > 0) {
      EXPECT_DOUBLE_EQ(iou(g.depth_dynamic_mask, g.dynamic_mask), 1.0) << "frame " << i;
    }
    if (cv::countNonZero(f.dynamic_mask) < 5000) continue;
    ++frames;
    const double overlap = iou(f.depth_dynamic_mask, f.dynamic_mask);
    EXPECT_GT(overlap, 0.3) << "frame " << i;  // the same people, a few pixels off
    if (overlap < 0.97) ++shifted;
  }
  ASSERT_GE(frames, 4);
  EXPECT_GE(shifted, frames / 2);
}

TEST(Sequence, CompositeWritesAVoidMaskPerFrame) {
  std::string skip;
  std::optional<SequenceConfig> found = fr1_composite(false, skip);
  if (!found) GTEST_SKIP() << skip;
  SequenceConfig config = *found;
  config.frames = 3;
  const TempDir dir("ddl_composite_void");
  write_sequence(*make_sequence_source(config), dir.str());
  const auto rows = io::read_text_table((dir.path() / "void_mask.txt").string());
  ASSERT_EQ(rows.size(), 3u);
  // The real accelerometer's readings over those frames, unchanged.
  const io::AccelerometerLog written =
      io::AccelerometerLog::read((dir.path() / "accelerometer.txt").string());
  const io::AccelerometerLog original =
      io::AccelerometerLog::read(config.background_dir + "/accelerometer.txt");
  ASSERT_FALSE(written.empty());
  EXPECT_LT(written.samples().size(), original.samples().size() / 20);
  const double first = io::parse_double(rows.front().fields[0], "void_mask.txt", 1);
  const double last = io::parse_double(rows.back().fields[0], "void_mask.txt", 3);
  for (const io::AccelerometerSample& a : written.samples()) {
    ASSERT_GE(a.timestamp_s, first - 0.051);
    ASSERT_LE(a.timestamp_s, last + 0.051);
    const auto same = std::find_if(original.samples().begin(), original.samples().end(),
                                   [&](const io::AccelerometerSample& o) {
                                     return std::abs(o.timestamp_s - a.timestamp_s) < 1e-6;
                                   });
    ASSERT_NE(same, original.samples().end());
    EXPECT_LT((same->specific_force - a.specific_force).norm(), 1e-5);
  }
  for (const auto& row : rows) {
    const cv::Mat mask = cv::imread((dir.path() / row.fields[1]).string(), cv::IMREAD_UNCHANGED);
    EXPECT_EQ(mask.type(), CV_8UC1) << row.fields[1];
    EXPECT_EQ(mask.size(), cv::Size(640, 480)) << row.fields[1];
  }
  // A synthetic room has nothing void and writes no list.
  const TempDir room_dir("ddl_room_no_void");
  write_sequence(*make_sequence_source(small_config("syn_static_static", 2)), room_dir.str());
  EXPECT_FALSE(fs::exists(room_dir.path() / "void_mask.txt"));
  EXPECT_FALSE(fs::exists(room_dir.path() / "void_mask"));
}

#ifdef DDL_HAVE_SEGMENTATION
// fr1_rpy shows a man seated at the far desk: a person, so DDL-SLAM rightly masks him, but not
// part of the composite's dynamic truth. The preset's void box must cover what the CNN takes for
// a person on the real frames (outside the drawn people), and only about that.
TEST(Sequence, CompositeVoidCoversTheRealSeatedMan) {
  const segmentation::SegmenterConfig seg_config;
  std::string skip;
  std::optional<SequenceConfig> found = fr1_composite(true, skip);
  if (!found) GTEST_SKIP() << skip;
  if (!fs::exists(fs::path(testing::shared_dir()) / seg_config.model_path)) {
    GTEST_SKIP() << "segmentation model not found in " << testing::shared_dir();
  }
  SequenceConfig config = *found;
  ASSERT_FALSE(config.void_boxes_w.empty());
  const auto source = make_sequence_source(config);
  const auto segmenter = segmentation::make_segmenter(seg_config, testing::shared_dir());
  const int kPerson = 15;  // PASCAL VOC
  long person_px = 0, person_in_void = 0, void_px = 0;
  // Frames where the man is in view, some partly behind a drawn person (237, 643).
  for (const std::size_t i : {148u, 237u, 313u, 533u, 643u, 683u}) {
    const FrameData f = source->render_frame(i);
    ASSERT_FALSE(f.void_mask.empty());
    cv::Mat both;
    cv::bitwise_and(f.void_mask, f.dynamic_mask, both);
    EXPECT_EQ(cv::countNonZero(both), 0) << "frame " << i << ": a drawn person is scored";
    const cv::Mat labels = segmenter->segment(f.background_rgb, "").labels;
    cv::Mat person = labels == kPerson;
    person.setTo(0, f.dynamic_mask);
    cv::Mat covered;
    cv::bitwise_and(person, f.void_mask, covered);
    person_px += cv::countNonZero(person);
    person_in_void += cv::countNonZero(covered);
    void_px += cv::countNonZero(f.void_mask);
  }
  ASSERT_GT(person_px, 10000);
  EXPECT_GT(static_cast<double>(person_in_void) / static_cast<double>(person_px), 0.85);
  EXPECT_LT(void_px, 3 * person_in_void) << "the void is much larger than the man";
  // Frames of the first second look at the desk, away from him: nothing void.
  EXPECT_EQ(cv::countNonZero(source->render_frame(10).void_mask), 0);
}
#endif

// meta.json's settings list what the sequence was made with: a composite (any preset given a
// background sequence) lists the background and the people, not the room's camera path, camera,
// posters or box, which it does not use (until stop 15 it listed them too).
TEST(Sequence, ACompositesSettingsListOnlyWhatItUses) {
  SequenceConfig composite = find_preset("syn_walking_xyz").config;
  composite.background_dir = "/data/rgbd_dataset_freiburg1_rpy";
  const nlohmann::json c = composite.to_json();
  EXPECT_EQ(c["kind"], "composite");
  EXPECT_EQ(c["background_dir"], "/data/rgbd_dataset_freiburg1_rpy");
  EXPECT_EQ(c["background_camera"]["name"], "tum1");
  for (const char* key : {"seed", "frames", "people_dir", "depth", "walker_distance_near_m",
                          "walker_distance_far_m", "void_boxes_w"}) {
    EXPECT_TRUE(c.contains(key)) << key;
  }
  for (const char* key :
       {"motion", "loop_turns", "camera", "poster_images", "moving_object", "object_move_start_s",
        "rgb_noise_sigma", "start_stamp_s", "depth_stamp_jitter_s", "people"}) {
    EXPECT_FALSE(c.contains(key)) << key;
  }
  const nlohmann::json room = find_preset("syn_walking_xyz").config.to_json();
  EXPECT_EQ(room["kind"], "room");
  EXPECT_EQ(room["motion"], "xyz");
  EXPECT_EQ(room["camera"]["name"], "tum3_synthetic");
  EXPECT_FALSE(room.contains("background_dir"));
  EXPECT_FALSE(room.contains("void_boxes_w"));
}

TEST(Sequence, PresetsMirrorTheBenchmarkRows) {
  std::set<std::string> names;
  for (const auto& p : presets()) {
    EXPECT_TRUE(names.insert(p.name).second) << p.name;
    if (p.background_in_shared.empty()) {
      // TUM-like lengths (20-30 s); the loop goes on past its start for a fifth of a turn.
      EXPECT_GE(p.config.frames, 600) << p.name;
      EXPECT_LE(p.config.frames, p.config.motion == MotionType::kLoop ? 1080 : 900) << p.name;
      EXPECT_NO_THROW(p.config.validate()) << p.name;
    }
  }
  for (const char* name :
       {"syn_walking_xyz", "syn_walking_static", "syn_walking_rpy", "syn_walking_halfsphere",
        "syn_sitting_static", "syn_sitting_halfsphere", "syn_desk_person", "syn_static_xyz",
        "syn_static_static", "syn_static_rpy", "syn_static_halfsphere", "syn_static_loop",
        "composite_fr1_rpy_walking"}) {
    EXPECT_TRUE(names.count(name)) << name;
  }
  try {
    find_preset("syn_walking_zigzag");
    FAIL() << "expected a ConfigError";
  } catch (const std::exception& e) {
    EXPECT_NE(std::string(e.what()).find("preset"), std::string::npos);
    EXPECT_NE(std::string(e.what()).find("syn_walking_xyz"), std::string::npos);
  }
  SequenceConfig bad = find_preset("syn_static_xyz").config;
  bad.depth_stamp_jitter_s = 0.02;
  EXPECT_THROW(bad.validate(), ConfigError);
  // Void boxes: only a composite has real content to leave unscored; bounds must be ordered.
  using test_support::throws_config_error_for_key;
  SequenceConfig room = find_preset("syn_static_xyz").config;
  room.void_boxes_w = {{Vec3d(0, 0, 0), Vec3d(1, 1, 1)}};
  EXPECT_TRUE(throws_config_error_for_key([&] { room.validate(); }, "void_boxes_w"));
  SequenceConfig composite = find_preset("composite_fr1_rpy_walking").config;
  composite.background_dir = "/somewhere";
  EXPECT_NO_THROW(composite.validate());
  composite.void_boxes_w.push_back({Vec3d(0, 0, 1), Vec3d(1, 1, 1)});
  EXPECT_TRUE(throws_config_error_for_key([&] { composite.validate(); }, "void_boxes_w[1]"));
}

TEST(Sequence, MissingBackgroundIsAClearInputError) {
  SequenceConfig config = find_preset("composite_fr1_rpy_walking").config;
  config.background_dir = "/nonexistent/tum_sequence";
  try {
    make_sequence_source(config);
    FAIL() << "expected an InputError";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent/tum_sequence"), std::string::npos)
        << e.what();
  }
}

}  // namespace
}  // namespace ddl::synthetic
