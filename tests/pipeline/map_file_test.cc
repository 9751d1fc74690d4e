// The sparse map on disk (map/map_file.h) and its reuse by a later run (System::load_map,
// tracking.localization_only): a map built by the whole system on a synthetic sequence is saved,
// loaded back unchanged, refused when damaged or made for another camera, and a second session
// relocalizes in it and tracks along the true trajectory, with or without extending it.

#include "ddl/map/map_file.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <string>
#include <vector>

#include "ddl/core/binary_file.h"
#include "ddl/core/error.h"
#include "ddl/pipeline/system.h"
#include "pipeline_test_support.h"

namespace ddl::pipeline {
namespace {

using testing::default_vocabulary;

/// The SLAM core with the geometry check (no CNN) and the octree: keyframes keep their depth
/// images, and the dense stage its scans, which the map file stores beside them.
SystemConfig core_config() {
  SystemConfig config = testing::core_config();
  config.dynamic.enabled = true;
  config.dynamic.use_segmentation = false;
  config.dense.octomap_enabled = true;
  return config;
}

// syn_static_rpy: rotations about a nearly fixed position, so later frames see mapped parts.
constexpr int kFrames = 180;
constexpr std::size_t kMapFrames = 120;  // the first session maps frames 0..119

std::filesystem::path temp_path(const std::string& name) {
  return std::filesystem::temp_directory_path() /
         ("ddl_map_file_test_" + std::to_string(::getpid()) + "_" + name);
}

std::vector<unsigned char> read_bytes(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

void write_bytes(const std::filesystem::path& path, const std::vector<unsigned char>& bytes) {
  std::ofstream out(path, std::ios::binary);
  out.write(reinterpret_cast<const char*>(bytes.data()),
            static_cast<std::streamsize>(bytes.size()));
}

/// The first session, run once for every test: frames 0..kMapFrames-1, the map saved.
struct Session {
  std::unique_ptr<synthetic::SequenceSource> source;
  std::filesystem::path map_path;
  std::unique_ptr<System> system;
  std::map<double, SE3> truth;  // T_w_c by timestamp, the generator's world
  ~Session() {
    std::error_code ec;
    if (!map_path.empty()) std::filesystem::remove(map_path, ec);
  }
};

Session& first_session() {
  static const std::unique_ptr<Session> session = [] {
    auto s = std::make_unique<Session>();
    s->source = synthetic::make_sequence_source(testing::preset_config("syn_static_rpy", kFrames));
    for (std::size_t i = 0; i < s->source->frame_count(); ++i) {
      const synthetic::FrameData data = s->source->render_frame(i);
      s->truth[data.rgb_stamp_s] = data.T_w_c;
    }
    s->system = std::make_unique<System>(core_config(), s->source->camera(), default_vocabulary());
    for (std::size_t i = 0; i < kMapFrames; ++i) {
      s->system->process(testing::to_rgbd(s->source->render_frame(i), s->source->camera()));
    }
    s->system->finish();
    s->map_path = temp_path("session1.ddlmap");
    s->system->save_map(s->map_path.string());
    return s;
  }();
  return *session;
}

/// Worst pose error of a run's trajectory against the truth, in the first session's world (the
/// camera of frame 0).
testing::PoseError worst_error(const io::Trajectory& trajectory, const Session& s) {
  const SE3 T_c0_w = s.truth.begin()->second.inverse();
  testing::PoseError worst;
  for (const io::StampedPose& pose : trajectory) {
    const auto it = s.truth.find(pose.timestamp_s);
    EXPECT_NE(it, s.truth.end());
    if (it == s.truth.end()) continue;
    const testing::PoseError e = testing::pose_error(pose.T_w_c(), T_c0_w * it->second);
    worst.translation_m = std::max(worst.translation_m, e.translation_m);
    worst.rotation_deg = std::max(worst.rotation_deg, e.rotation_deg);
  }
  return worst;
}

TEST(MapFile, ALoadedMapHoldsTheSavedKeyframesPointsAndTree) {
  if (!default_vocabulary()) GTEST_SKIP() << "vocab/ddl_orb_k10_l5.dvoc is absent";
  const Session& s = first_session();
  const map::Map& saved = *s.system->map();
  map::Map loaded;
  const map::MapFileContents contents = map::load_map_file(s.map_path.string(), loaded);
  EXPECT_EQ(contents.info.image_width, s.source->camera().width);
  EXPECT_DOUBLE_EQ(contents.info.fx, s.source->camera().fx);
  EXPECT_EQ(contents.info.vocabulary_words, default_vocabulary()->word_count());
  // Every keyframe's depth image, to TUM's 0.2 mm unit.
  EXPECT_EQ(contents.images.size(), contents.keyframes);
  for (const auto& [id, images] : contents.images) {
    const std::optional<map::KeyFrameImages> original =
        s.system->dynamic_front_end().keyframe_images(id);
    ASSERT_TRUE(original.has_value()) << "keyframe " << id;
    EXPECT_LE(cv::norm(original->depth_m, images.depth_m, cv::NORM_INF), 0.5 / 5000.0 + 1e-6);
    EXPECT_EQ(cv::countNonZero(original->depth_m > 0), cv::countNonZero(images.depth_m > 0));
  }

  const std::vector<map::KeyFramePtr> a = saved.keyframes();
  const std::vector<map::KeyFramePtr> b = loaded.keyframes();
  ASSERT_GT(a.size(), 5u);
  ASSERT_EQ(a.size(), b.size());
  EXPECT_EQ(contents.keyframes, a.size());
  for (std::size_t k = 0; k < a.size(); ++k) {
    SCOPED_TRACE("keyframe " + std::to_string(a[k]->id()));
    ASSERT_EQ(a[k]->id(), b[k]->id());
    EXPECT_EQ(a[k]->timestamp_s(), b[k]->timestamp_s());
    EXPECT_EQ(a[k]->is_origin(), b[k]->is_origin());
    EXPECT_LT(testing::pose_error(a[k]->T_w_c(), b[k]->T_w_c()).translation_m, 1e-12);
    EXPECT_LT(testing::pose_error(a[k]->T_w_c(), b[k]->T_w_c()).rotation_deg, 1e-9);
    const map::FrameFeatures& fa = a[k]->features();
    const map::FrameFeatures& fb = b[k]->features();
    ASSERT_EQ(fa.size(), fb.size());
    for (std::size_t i = 0; i < fa.size(); ++i) {
      EXPECT_EQ(fa.keypoints[i].pt, fb.keypoints[i].pt);
      EXPECT_EQ(fa.keypoints[i].octave, fb.keypoints[i].octave);
      EXPECT_EQ(fa.keypoints[i].angle, fb.keypoints[i].angle);
      EXPECT_EQ(fa.depth_m[i], fb.depth_m[i]);
      EXPECT_EQ(fa.u_right[i], fb.u_right[i]);
    }
    EXPECT_EQ(cv::norm(fa.descriptors, fb.descriptors, cv::NORM_HAMMING), 0.0);
    EXPECT_EQ(fa.pyramid.scale_factors, fb.pyramid.scale_factors);
    const map::KeyFramePtr pa = a[k]->parent();
    const map::KeyFramePtr pb = b[k]->parent();
    ASSERT_EQ(pa == nullptr, pb == nullptr);
    if (pa) {
      EXPECT_EQ(pa->id(), pb->id());
    }
    // The covisibility graph is rebuilt from the observations: every keyframe but a lone one
    // has links again.
    EXPECT_FALSE(b[k]->covisibles().empty());
  }

  const std::vector<map::MapPointPtr> pa = saved.map_points();
  const std::vector<map::MapPointPtr> pb = loaded.map_points();
  ASSERT_EQ(pa.size(), pb.size());
  EXPECT_EQ(contents.map_points, pa.size());
  for (std::size_t k = 0; k < pa.size(); ++k) {
    ASSERT_EQ(pa[k]->id(), pb[k]->id());
    EXPECT_EQ(pa[k]->position_w(), pb[k]->position_w());
    EXPECT_EQ(pa[k]->num_observations(), pb[k]->num_observations());
    EXPECT_EQ(pa[k]->found_count(), pb[k]->found_count());
    EXPECT_EQ(pa[k]->visible_count(), pb[k]->visible_count());
    const auto oa = pa[k]->observations();
    const auto ob = pb[k]->observations();
    ASSERT_EQ(oa.size(), ob.size());
    for (std::size_t i = 0; i < oa.size(); ++i) {
      EXPECT_EQ(oa[i].keyframe->id(), ob[i].keyframe->id());
      EXPECT_EQ(oa[i].feature_index, ob[i].feature_index);
      EXPECT_EQ(oa[i].stereo, ob[i].stereo);
    }
  }
  // New entities do not take the ids of loaded ones.
  EXPECT_GT(loaded.next_keyframe_id(), a.back()->id());
  EXPECT_GT(loaded.next_map_point_id(), pa.back()->id());

  // The dense stage's scans, every one anchored to a stored keyframe, with their images as the
  // stage kept them (depth to TUM's 0.2 mm unit).
  const std::vector<map::DenseScan> kept = s.system->dense_mapper().dense_scans();
  ASSERT_GE(kept.size(), contents.keyframes);
  ASSERT_EQ(contents.dense_scans.size(), kept.size());
  EXPECT_EQ(contents.version, 2u);
  for (std::size_t k = 0; k < kept.size(); ++k) {
    const map::DenseScan& a = kept[k];
    const map::DenseScan& b = contents.dense_scans[k];
    EXPECT_EQ(a.anchor, b.anchor);
    EXPECT_NE(loaded.keyframe(b.anchor), nullptr);
    EXPECT_LT(testing::pose_error(a.T_anchor_c, b.T_anchor_c).translation_m, 1e-12);
    EXPECT_EQ(a.pixel_step, b.pixel_step);
    EXPECT_EQ(cv::norm(a.bgr, b.bgr, cv::NORM_INF), 0.0);
    EXPECT_LE(cv::norm(a.depth_m, b.depth_m, cv::NORM_INF), 0.5 / 5000.0 + 1e-6);
    EXPECT_EQ(cv::countNonZero(a.exclude), cv::countNonZero(b.exclude));
  }

  // Saved again, the loaded map gives the same file.
  const auto again = temp_path("again.ddlmap");
  map::MapFileInfo info = contents.info;
  map::save_map_file(
      loaded, info, again.string(),
      [&](map::KeyFrameId id) -> std::optional<map::KeyFrameImages> {
        const auto it = contents.images.find(id);
        if (it == contents.images.end()) return std::nullopt;
        return it->second;
      },
      contents.dense_scans);
  EXPECT_TRUE(read_bytes(again) == read_bytes(s.map_path));
  std::filesystem::remove(again);
}

// Version 1 files (stop 30, before the dense scans) are still read: the same map without scans.
TEST(MapFile, AVersionOneFileIsReadWithoutDenseScans) {
  if (!default_vocabulary()) GTEST_SKIP() << "vocab/ddl_orb_k10_l5.dvoc is absent";
  const Session& s = first_session();
  map::Map plain;
  map::MapFileContents contents = map::load_map_file(s.map_path.string(), plain);
  const auto path = temp_path("v1.ddlmap");
  // Without scans the file ends with the scan count (8 zero bytes) and the padding: dropping the
  // count and setting version 1 gives the version 1 layout.
  map::save_map_file(plain, contents.info, path.string(),
                     [&](map::KeyFrameId id) -> std::optional<map::KeyFrameImages> {
                       const auto it = contents.images.find(id);
                       if (it == contents.images.end()) return std::nullopt;
                       return it->second;
                     });
  std::vector<unsigned char> bytes = read_bytes(path);
  ASSERT_GE(bytes.size(), 112u);
  bytes.erase(bytes.end() - 16, bytes.end() - 8);
  const std::uint32_t version = 1;
  std::memcpy(bytes.data() + 8, &version, sizeof(version));
  const std::uint64_t sum = checksum64(bytes.data(), bytes.size() - 8);
  std::memcpy(bytes.data() + bytes.size() - 8, &sum, 8);
  write_bytes(path, bytes);
  map::Map map;
  const map::MapFileContents v1 = map::load_map_file(path.string(), map);
  std::filesystem::remove(path);
  EXPECT_EQ(v1.version, 1u);
  EXPECT_EQ(v1.keyframes, contents.keyframes);
  EXPECT_EQ(v1.map_points, contents.map_points);
  EXPECT_EQ(v1.images.size(), contents.images.size());
  EXPECT_TRUE(v1.dense_scans.empty());
}

// A scan whose images do not fit the camera at its stride is a programming error of the writer,
// not a file it writes; a scan anchored to a keyframe the file does not hold is left out.
TEST(MapFile, DenseScansAreCheckedWhenWrittenAndLeftOutWithoutTheirAnchor) {
  if (!default_vocabulary()) GTEST_SKIP() << "vocab/ddl_orb_k10_l5.dvoc is absent";
  const Session& s = first_session();
  map::Map plain;
  const map::MapFileContents contents = map::load_map_file(s.map_path.string(), plain);
  ASSERT_FALSE(contents.dense_scans.empty());
  const auto path = temp_path("scans.ddlmap");
  std::vector<map::DenseScan> scans{contents.dense_scans.front()};
  scans.front().bgr = cv::Mat(10, 10, CV_8UC3, cv::Scalar::all(0));
  EXPECT_THROW(map::save_map_file(plain, contents.info, path.string(), {}, scans), Error);
  scans = {contents.dense_scans.front(), contents.dense_scans.front()};
  scans[1].anchor = 1u << 30;  // no such keyframe
  map::save_map_file(plain, contents.info, path.string(), {}, scans);
  map::Map map;
  const map::MapFileContents read = map::load_map_file(path.string(), map);
  std::filesystem::remove(path);
  EXPECT_EQ(read.dense_scans.size(), 1u);
}

TEST(MapFile, ADamagedOrForeignFileIsRefusedWithItsName) {
  if (!default_vocabulary()) GTEST_SKIP() << "vocab/ddl_orb_k10_l5.dvoc is absent";
  const Session& s = first_session();
  const std::vector<unsigned char> good = read_bytes(s.map_path);
  const auto bad = temp_path("bad.ddlmap");
  const auto expect_refused = [&](const std::vector<unsigned char>& bytes, const char* what) {
    write_bytes(bad, bytes);
    map::Map map;
    try {
      map::load_map_file(bad.string(), map);
      ADD_FAILURE() << "accepted: " << what;
    } catch (const InputError& e) {
      const std::string message = e.what();
      EXPECT_NE(message.find(bad.string()), std::string::npos) << message;
      EXPECT_NE(message.find(what), std::string::npos) << message;
    }
    EXPECT_EQ(map.keyframe_count(), 0u);
    EXPECT_EQ(map.map_point_count(), 0u);
  };
  std::vector<unsigned char> flipped = good;
  flipped[flipped.size() / 2] ^= 0x10;
  expect_refused(flipped, "checksum mismatch");
  expect_refused(std::vector<unsigned char>(good.begin(), good.begin() + good.size() / 2 / 8 * 8),
                 "checksum mismatch");
  std::vector<unsigned char> magic = good;
  magic[0] = 'X';
  expect_refused(magic, "not a DDL-SLAM map file");
  std::vector<unsigned char> version = good;
  version[8] = 9;
  expect_refused(version, "unsupported map file version 9");
  expect_refused({}, "not a DDL-SLAM map file");
  // Checks beyond the checksum: the origin (the first keyframe, whose parent field follows the
  // 96-byte header, its id, stamp and pose) given a parent, with the checksum made right again.
  std::vector<unsigned char> rooted = good;
  std::memcpy(rooted.data() + 96 + 72, rooted.data() + 96, 8);  // parent = its own id
  const std::uint64_t sum = checksum64(rooted.data(), rooted.size() - 8);
  std::memcpy(rooted.data() + rooted.size() - 8, &sum, 8);
  expect_refused(rooted, "the origin has a parent");
  std::filesystem::remove(bad);

  map::Map missing;
  EXPECT_THROW(map::load_map_file(temp_path("absent.ddlmap").string(), missing), InputError);

  // A system whose camera differs refuses the map before the first frame.
  camera::PinholeCamera other = s.source->camera();
  other.fx *= 1.1;
  System system(core_config(), other, default_vocabulary());
  try {
    system.load_map(s.map_path.string());
    ADD_FAILURE() << "a map of another camera was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("another camera"), std::string::npos) << e.what();
  }
  EXPECT_EQ(system.map()->keyframe_count(), 0u);
}

TEST(MapFile, LocalizationOnlyRelocalizesInTheSavedMapAndTracksWithoutChangingIt) {
  if (!default_vocabulary()) GTEST_SKIP() << "vocab/ddl_orb_k10_l5.dvoc is absent";
  const Session& s = first_session();
  SystemConfig config = core_config();
  config.tracking.localization_only = true;
  System system(config, s.source->camera(), default_vocabulary());
  const map::MapFileContents contents = system.load_map(s.map_path.string());
  // A second session starting mid-way, with no motion to continue from: frames 60..179, the
  // last 60 of them beyond what the first session saw.
  std::size_t first_tracked = 0;
  for (std::size_t i = 60; i < kFrames; ++i) {
    const FrameOutcome outcome =
        system.process(testing::to_rgbd(s.source->render_frame(i), s.source->camera()));
    if (first_tracked == 0 && outcome.tracking.tracked()) first_tracked = i;
  }
  system.finish();
  const SystemStatistics stats = system.statistics();
  std::printf("relocalized at frame %zu; %zu of %zu frames tracked, %zu lost, %zu keyframes\n",
              first_tracked, stats.poses, stats.frames, stats.frames_lost, stats.keyframes);
  EXPECT_EQ(first_tracked, 60u) << "the first frame did not relocalize in the loaded map";
  EXPECT_EQ(stats.frames_lost, 0u);
  EXPECT_EQ(stats.keyframes_created, 0u);
  EXPECT_EQ(stats.keyframes, contents.keyframes);
  EXPECT_EQ(stats.keyframes_loaded, contents.keyframes);
  // The stored depth images are the geometry check's references: it runs on every frame.
  EXPECT_EQ(stats.keyframe_depth_images_loaded, contents.keyframes);
  EXPECT_EQ(stats.geometry_checks_without_reference, 0u);
  EXPECT_GE(stats.geometry_checks_low_cost + stats.geometry_checks_predicted, stats.frames - 1);
  // No keyframe of its own, but the octree of the map it loaded (the first session's, up to the
  // poses local BA gave keyframes after they went into that octree).
  EXPECT_EQ(stats.dense.scans_loaded, contents.dense_scans.size());
  const std::size_t first = s.system->dense_mapper().octree()->stats().occupied_leaves;
  const std::size_t now = system.dense_mapper().octree()->stats().occupied_leaves;
  std::printf("octree: %zu occupied voxels, the first session's %zu\n", now, first);
  EXPECT_GT(first, 1000u);
  EXPECT_NEAR(static_cast<double>(now), static_cast<double>(first), 0.02 * first);
  const testing::PoseError worst = worst_error(system.camera_trajectory(), s);
  std::printf("worst error %.4f m, %.3f deg\n", worst.translation_m, worst.rotation_deg);
  EXPECT_LT(worst.translation_m, 0.03);
  EXPECT_LT(worst.rotation_deg, 1.5);
}

TEST(MapFile, ALoadedMapIsExtendedByALaterSession) {
  if (!default_vocabulary()) GTEST_SKIP() << "vocab/ddl_orb_k10_l5.dvoc is absent";
  const Session& s = first_session();
  System system(core_config(), s.source->camera(), default_vocabulary());
  const map::MapFileContents contents = system.load_map(s.map_path.string());
  map::KeyFrameId max_loaded = 0;
  for (const map::KeyFramePtr& kf : system.map()->keyframes()) {
    max_loaded = std::max(max_loaded, kf->id());
  }
  for (std::size_t i = 100; i < kFrames; ++i) {
    system.process(testing::to_rgbd(s.source->render_frame(i), s.source->camera()));
  }
  system.finish();
  const SystemStatistics stats = system.statistics();
  EXPECT_EQ(stats.frames_lost, 0u);
  EXPECT_GT(stats.keyframes_created, 0u);
  EXPECT_EQ(stats.map_resets, 0u);
  std::size_t new_keyframes = 0;
  for (const map::KeyFramePtr& kf : system.map()->keyframes()) {
    if (kf->id() > max_loaded) ++new_keyframes;
  }
  EXPECT_GT(new_keyframes, 0u);
  EXPECT_GT(stats.keyframes, contents.keyframes / 2);  // culling may drop some loaded ones
  const testing::PoseError worst = worst_error(system.camera_trajectory(), s);
  std::printf("%zu new keyframes; worst error %.4f m, %.3f deg\n", new_keyframes,
              worst.translation_m, worst.rotation_deg);
  EXPECT_LT(worst.translation_m, 0.03);
  EXPECT_LT(worst.rotation_deg, 1.5);
}

TEST(MapFile, LocalizationOnlyWithoutALoadedMapIsAConfigurationError) {
  if (!default_vocabulary()) GTEST_SKIP() << "vocab/ddl_orb_k10_l5.dvoc is absent";
  const auto source = synthetic::make_sequence_source(testing::preset_config("syn_static_rpy", 2));
  SystemConfig config = core_config();
  config.tracking.localization_only = true;
  System system(config, source->camera(), default_vocabulary());
  EXPECT_THROW(system.process(testing::to_rgbd(source->render_frame(0), source->camera())),
               ConfigError);
}

}  // namespace
}  // namespace ddl::pipeline
