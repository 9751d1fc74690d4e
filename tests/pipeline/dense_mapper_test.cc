#include "ddl/pipeline/dense_mapper.h"

#include <fmt/format.h>
#include <gtest/gtest.h>
#include <octomap/ColorOcTree.h>

#include <filesystem>
#include <fstream>
#include <iterator>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <string>
#include <tuple>
#include <vector>

#include "ddl/core/error.h"
#include "ddl/map/map.h"
#include "ddl/synthetic/sequence.h"

namespace ddl::pipeline {
namespace {

// The dense stage shares the keyframe's images and mask with tracking and dynamic removal (the
// dynamic memory and the geometry check keep the keyframe's mask): it must never write into them.
// Before 2026-11-26 the border band around the mask was assigned into the caller's mask buffer
// when inpainting was off, so the keyframe masks those stages kept grew by mask_border_px.
TEST(DenseMapper, LeavesTheSubmittedImagesAndMaskUntouched) {
  const camera::PinholeCamera camera = synthetic::tum3_camera();
  for (const bool inpainting : {false, true}) {
    for (const bool own_thread : {false, true}) {
      auto map = std::make_shared<map::Map>();
      DenseMapperConfig config;
      config.inpainting_enabled = inpainting;
      config.octomap_enabled = true;
      config.mask_border_px = 12;
      config.deterministic_thread = own_thread;
      DenseMapper dense(config, camera, map);
      // Checked after finish(): the stage's thread may still be working at submit()'s return.
      std::vector<std::pair<cv::Mat, cv::Mat>> images;  // {submitted, copy from before}
      for (int k = 0; k < 3; ++k) {
        const SE3 T_c_w(Mat3d::Identity(), Vec3d(0.05 * k, 0.0, 0.0));
        auto kf = std::make_shared<map::KeyFrame>(map->next_keyframe_id(), k,
                                                  std::make_shared<map::FrameFeatures>(), T_c_w);
        map->add_keyframe(kf);
        cv::Mat bgr(camera.height, camera.width, CV_8UC3, cv::Scalar(40, 80, 120));
        cv::Mat depth(camera.height, camera.width, CV_32FC1, cv::Scalar(2.0f));
        cv::Mat mask = cv::Mat::zeros(camera.height, camera.width, CV_8UC1);
        cv::rectangle(mask, cv::Rect(200 + 20 * k, 150, 120, 200), cv::Scalar(255), cv::FILLED);
        depth.setTo(1.2f, mask);
        const cv::Mat bgr_before = bgr.clone();
        const cv::Mat depth_before = depth.clone();
        const cv::Mat mask_before = mask.clone();
        dense.submit({kf, bgr, depth, mask});
        images.emplace_back(mask, mask_before);
        images.emplace_back(depth, depth_before);
        images.emplace_back(bgr.reshape(1), bgr_before.reshape(1));
      }
      dense.finish();
      EXPECT_EQ(dense.stats().keyframes, 3u);
      for (const auto& [after, before] : images) {
        EXPECT_EQ(cv::countNonZero(after != before), 0)
            << "inpainting " << inpainting << ", own thread " << own_thread;
      }
    }
  }
}

// A map file that cannot be written (a folder stands in map.ot's place) does not stop the others:
// its error is returned, the rest are written whole and listed.
TEST(DenseMapper, AMapFileThatCannotBeWrittenDoesNotStopTheOthers) {
  const camera::PinholeCamera camera = synthetic::tum3_camera();
  auto map = std::make_shared<map::Map>();
  DenseMapperConfig config;
  config.octomap_enabled = true;
  config.octree_delay_keyframes = 0;
  DenseMapper dense(config, camera, map);
  auto kf = std::make_shared<map::KeyFrame>(map->next_keyframe_id(), 0,
                                            std::make_shared<map::FrameFeatures>(), SE3());
  map->add_keyframe(kf);
  const cv::Mat bgr(camera.height, camera.width, CV_8UC3, cv::Scalar(40, 80, 120));
  const cv::Mat depth(camera.height, camera.width, CV_32FC1, cv::Scalar(2.0f));
  dense.submit({kf, bgr, depth, cv::Mat::zeros(camera.height, camera.width, CV_8UC1)});
  dense.finish();
  const std::filesystem::path dir =
      std::filesystem::path(::testing::TempDir()) / "dense_mapper_outputs";
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir / "map.ot");
  std::vector<std::string> errors;
  const std::vector<std::string> written = dense.write_outputs(dir.string(), errors);
  ASSERT_EQ(errors.size(), 1u);
  EXPECT_NE(errors[0].find("map.ot"), std::string::npos) << errors[0];
  ASSERT_EQ(written.size(), 4u);
  for (const std::string& f : written) {
    EXPECT_TRUE(std::filesystem::is_regular_file(f)) << f;
    EXPECT_GT(std::filesystem::file_size(f), 0u) << f;
  }
  EXPECT_TRUE(std::filesystem::is_directory(dir / "map.ot"));
}

// A map reset (tracking lost while the map was young) starts a new world frame: the keyframes
// stored before it must neither fill later keyframes nor stay in the octree. Until 2026-11-26 the
// dense stage was not told, and pasted old-frame pixels and kept old-frame voxels.
TEST(DenseMapper, AMapResetDropsTheStoredKeyframesAndTheOctree) {
  const camera::PinholeCamera camera = synthetic::tum3_camera();
  auto keyframe_images = [&](int k, bool masked) {
    cv::Mat bgr(camera.height, camera.width, CV_8UC3, cv::Scalar(40 + 30 * k, 80, 120));
    cv::Mat depth(camera.height, camera.width, CV_32FC1, cv::Scalar(2.0f + 0.3f * k));
    cv::Mat mask = cv::Mat::zeros(camera.height, camera.width, CV_8UC1);
    if (masked) {
      cv::rectangle(mask, cv::Rect(260, 180, 100, 120), cv::Scalar(255), cv::FILLED);
      depth.setTo(1.0f, mask);
    }
    return std::make_tuple(bgr, depth, mask);
  };
  for (const bool threaded : {false, true}) {
    auto run = [&](bool with_old_keyframes, bool reset) {
      auto map = std::make_shared<map::Map>();
      DenseMapperConfig config;
      config.threaded = threaded;
      config.mask_border_px = 0;
      auto dense = std::make_unique<DenseMapper>(config, camera, map);
      auto submit = [&](int k, bool masked) {
        auto kf = std::make_shared<map::KeyFrame>(map->next_keyframe_id(), k,
                                                  std::make_shared<map::FrameFeatures>(), SE3());
        map->add_keyframe(kf);
        auto [bgr, depth, mask] = keyframe_images(k, masked);
        dense->submit({kf, bgr, depth, mask});
      };
      if (with_old_keyframes) {
        submit(0, false);
        submit(1, false);
      }
      if (reset) dense->reset();
      submit(2, true);
      dense->finish();
      return dense;
    };
    const auto fresh = run(false, false);
    const auto kept = run(true, false);
    const auto reset = run(true, true);
    // Without the reset the old keyframes fill the new keyframe's masked pixels.
    EXPECT_GT(kept->stats().filled_pixels, 10000) << "threaded " << threaded;
    EXPECT_EQ(reset->stats().filled_pixels, 0) << "threaded " << threaded;
    EXPECT_EQ(reset->stats().resets, 1u);
    EXPECT_EQ(reset->stats().keyframes, 3u);
    ASSERT_NE(reset->octree(), nullptr);
    EXPECT_EQ(reset->octree()->stats().scans_integrated, 1u) << "threaded " << threaded;
    EXPECT_EQ(reset->octree()->stats().occupied_leaves, fresh->octree()->stats().occupied_leaves)
        << "threaded " << threaded;
    EXPECT_NE(kept->octree()->stats().occupied_leaves, fresh->octree()->stats().occupied_leaves);
  }
}

// Review finding (stop 20): keyframes went into the octree at their tracking pose, before local
// BA refined it (by up to 2 cm on syn_walking_xyz), and the end of the run rebuilt the octree only
// after a loop closure. A keyframe now waits octree_delay_keyframes keyframes, goes in at the pose
// it has then, and the end of the run rebuilds when an integrated keyframe moved by more than a
// quarter voxel since.
TEST(DenseMapper, KeyframesGoIntoTheOctreeAfterTheirDelayAtTheirPoseThen) {
  const camera::PinholeCamera camera = synthetic::tum3_camera();
  const auto pose = [](int k, double shift_m) {
    return SE3(Mat3d::Identity(), Vec3d(0.3 * k + shift_m, 0.0, 0.0));
  };
  struct Result {
    std::size_t scans_before_finish = 0;
    std::size_t rebuilds = 0;
    std::size_t timed_rebuilds = 0;  // timing_ms's octomap_rebuild count
    std::size_t occupied = 0;
  };
  // Four keyframes of a wall 2 m away; `late` = {keyframe, shift} moves one of them after all
  // four were submitted (as local BA would), before finish().
  const auto run = [&](int delay, std::pair<int, double> late, bool shift_before_submit) {
    auto map = std::make_shared<map::Map>();
    DenseMapperConfig config;
    config.inpainting_enabled = false;
    config.octree_delay_keyframes = delay;
    config.deterministic_thread = false;  // the octree is read before finish()
    DenseMapper dense(config, camera, map);
    std::vector<map::KeyFramePtr> keyframes;
    for (int k = 0; k < 4; ++k) {
      const double shift = shift_before_submit && k == late.first ? late.second : 0.0;
      auto kf = std::make_shared<map::KeyFrame>(
          map->next_keyframe_id(), k, std::make_shared<map::FrameFeatures>(), pose(k, shift));
      map->add_keyframe(kf);
      keyframes.push_back(kf);
      cv::Mat bgr(camera.height, camera.width, CV_8UC3, cv::Scalar(40, 80, 120));
      cv::Mat depth(camera.height, camera.width, CV_32FC1, cv::Scalar(2.0f));
      dense.submit({kf, bgr, depth, cv::Mat()});
    }
    Result r;
    r.scans_before_finish = dense.octree()->stats().scans_integrated;
    if (!shift_before_submit) keyframes[late.first]->set_T_c_w(pose(late.first, late.second));
    dense.finish();
    r.rebuilds = dense.stats().octree_rebuilds;
    const auto timings = dense.timings().summary();
    const auto rebuilt = timings.find("octomap_rebuild");
    r.timed_rebuilds = rebuilt == timings.end() ? 0 : rebuilt->second.count;
    r.occupied = dense.octree()->stats().occupied_leaves;
    return r;
  };
  // Keyframe 3 moves 3 cm while it waits: it goes in at its new pose, no rebuild needed.
  const Result delayed = run(2, {3, 0.03}, false);
  EXPECT_EQ(delayed.scans_before_finish, 2u);
  EXPECT_EQ(delayed.rebuilds, 0u);
  const Result truth = run(0, {3, 0.03}, true);  // every keyframe at its final pose from the start
  EXPECT_EQ(truth.rebuilds, 0u);
  EXPECT_EQ(delayed.occupied, truth.occupied);
  // The premise: at its old pose keyframe 3 gives another map.
  EXPECT_NE(run(0, {3, 0.0}, true).occupied, truth.occupied);
  // Keyframe 0 moves 3 cm after it went in: the end of the run rebuilds; 5 mm (under a quarter of
  // the 5 cm voxel) does not.
  const Result moved = run(2, {0, 0.03}, false);
  EXPECT_EQ(moved.rebuilds, 1u);
  EXPECT_EQ(moved.timed_rebuilds, 1u) << "the rebuild at the end of the run is not timed";
  EXPECT_EQ(run(2, {0, 0.005}, false).rebuilds, 0u);
  // At once (delay 0), as before: all four in before finish().
  EXPECT_EQ(run(0, {0, 0.0}, false).scans_before_finish, 4u);
}

// Deterministic runs give the dense stage a thread of its own (dense.deterministic_thread) but
// take every pose it reads when the keyframe is submitted: the outputs are those of the inline
// stage although local BA and loop correction move the keyframes while the thread works. Each
// keyframe here is moved right after its submission, while the thread is still busy with it.
TEST(DenseMapper, ItsOwnThreadInADeterministicRunGivesTheInlineOutputs) {
  const camera::PinholeCamera camera = synthetic::tum3_camera();
  struct Outcome {
    DenseStats stats;
    octomap::OctreeStats octree;
  };
  // `moves`: keyframes move after their submission (0 = never). `moved_first`: submitted at the
  // moved poses instead (the outputs a stage reading poses late would risk).
  const auto run = [&](bool own_thread, double moves, bool moved_first) {
    auto map = std::make_shared<map::Map>();
    DenseMapperConfig config;
    config.deterministic_thread = own_thread;
    config.octree_delay_keyframes = 2;
    config.inpainting.num_keyframes = 3;
    config.inpainting.extra_keyframes = 1;
    DenseMapper dense(config, camera, map);
    // The moves alternate in direction, so they change the keyframes' relative poses.
    const auto pose = [](int k, double shift_m) {
      const double sign = k % 2 == 0 ? 1.0 : -1.0;
      return SE3(Mat3d::Identity(), Vec3d(0.05 * k + sign * shift_m, 0.01 * k, 0.0));
    };
    std::vector<map::KeyFramePtr> keyframes;
    for (int k = 0; k < 8; ++k) {
      auto kf = std::make_shared<map::KeyFrame>(map->next_keyframe_id(), k,
                                                std::make_shared<map::FrameFeatures>(),
                                                pose(k, moved_first ? moves : 0.0));
      map->add_keyframe(kf);
      keyframes.push_back(kf);
      cv::Mat bgr(camera.height, camera.width, CV_8UC3);
      cv::randu(bgr, cv::Scalar::all(0), cv::Scalar::all(255));
      cv::Mat depth(camera.height, camera.width, CV_32FC1, cv::Scalar(2.0f + 0.05f * k));
      cv::Mat mask = cv::Mat::zeros(camera.height, camera.width, CV_8UC1);
      cv::rectangle(mask, cv::Rect(180 + 25 * k, 140, 140, 200), cv::Scalar(255), cv::FILLED);
      depth.setTo(1.1f, mask);
      dense.submit({kf, bgr, depth, mask});
      // As local BA would, while the stage works on it; every third time as a loop correction.
      if (!moved_first) kf->set_T_c_w(pose(k, moves));
      if (k % 3 == 2) map->notify_big_change();
    }
    dense.finish();
    return Outcome{dense.stats(), dense.octree()->stats()};
  };
  const Outcome inline_stage = run(false, 0.04, false);
  const Outcome own_thread = run(true, 0.04, false);
  EXPECT_GT(inline_stage.stats.filled_pixels, 10000);
  EXPECT_EQ(own_thread.stats.filled_pixels, inline_stage.stats.filled_pixels);
  EXPECT_EQ(own_thread.stats.masked_pixels, inline_stage.stats.masked_pixels);
  EXPECT_EQ(own_thread.stats.octree_rebuilds, inline_stage.stats.octree_rebuilds);
  EXPECT_EQ(own_thread.octree.scans_integrated, inline_stage.octree.scans_integrated);
  EXPECT_EQ(own_thread.octree.occupied_leaves, inline_stage.octree.occupied_leaves);
  EXPECT_EQ(own_thread.octree.free_leaves, inline_stage.octree.free_leaves);
  // The premise: poses read after the moves give other outputs.
  const Outcome late = run(false, 0.04, true);
  EXPECT_NE(late.stats.filled_pixels, inline_stage.stats.filled_pixels);
}

// Review finding (stop 20): every keyframe stayed stored with its full images (about 3 MB at
// 640x480) for the whole run. Keyframes past the inpainting sources now keep only the pixels an
// octree rebuild uses; a rebuild from them gives the octree that full images give.
TEST(DenseMapper, OldKeyframesKeepOnlyWhatARebuildNeeds) {
  const camera::PinholeCamera camera = synthetic::tum3_camera();
  const int n = 12;
  const auto pose = [](int k, double shift_m) {
    return SE3(so3_exp(Vec3d(0.0, 0.02 * k, 0.0)), Vec3d(0.1 * k + shift_m, 0.0, 0.0));
  };
  const auto images = [&](int k) {
    cv::Mat bgr(camera.height, camera.width, CV_8UC3, cv::Scalar(40 + 10 * k, 80, 120));
    cv::Mat depth(camera.height, camera.width, CV_32FC1);
    for (int v = 0; v < depth.rows; ++v) {
      for (int u = 0; u < depth.cols; ++u) {
        depth.at<float>(v, u) = 1.5f + 0.002f * static_cast<float>(u + v) + 0.05f * k;
      }
    }
    cv::Mat mask = cv::Mat::zeros(camera.height, camera.width, CV_8UC1);
    cv::rectangle(mask, cv::Rect(200 + 10 * k, 150, 80, 120), cv::Scalar(255), cv::FILLED);
    return std::make_tuple(bgr, depth, mask);
  };
  // Submits the n keyframes, then moves keyframe 1 by 4 cm (after it went into the octree) and
  // finishes; returns the keyframes.
  const auto run = [&](map::Map& map, DenseMapper& dense) {
    std::vector<map::KeyFramePtr> keyframes;
    for (int k = 0; k < n; ++k) {
      auto kf = std::make_shared<map::KeyFrame>(
          map.next_keyframe_id(), k, std::make_shared<map::FrameFeatures>(), pose(k, 0.0));
      map.add_keyframe(kf);
      keyframes.push_back(kf);
      auto [bgr, depth, mask] = images(k);
      dense.submit({kf, bgr, depth, mask});
    }
    keyframes[1]->set_T_c_w(pose(1, 0.04));
    dense.finish();
    return keyframes;
  };
  auto map = std::make_shared<map::Map>();
  DenseMapperConfig config;
  config.inpainting.num_keyframes = 3;  // sources: the newest 3 + 2
  config.inpainting.extra_keyframes = 2;
  config.octree_delay_keyframes = 2;
  DenseMapper dense(config, camera, map);
  run(*map, dense);
  // Keyframe 1 moved after it went in: the end of the run rebuilds from the compacted keyframes.
  EXPECT_EQ(dense.stats().octree_rebuilds, 1u);
  // One full keyframe: colour, depth, exclusion and the repaired mask (the unfilled one shares
  // the exclusion's buffer or adds one more byte per pixel).
  const std::size_t full =
      static_cast<std::size_t>(camera.width) * camera.height * (3 + 4 + 1 + 1 + 1);
  EXPECT_LE(dense.stats().peak_stored_image_bytes, 6 * full + (n - 5) * full / 16 + full / 8);
  EXPECT_GE(dense.stats().peak_stored_image_bytes, 5 * full / 2);

  // Without inpainting every keyframe is compacted at once; the octree the end of the run rebuilds
  // from them is the one the full scans give, each at its final pose, outside the mask and its
  // border band.
  auto map_b = std::make_shared<map::Map>();
  DenseMapperConfig no_repair = config;
  no_repair.inpainting_enabled = false;
  DenseMapper compacted(no_repair, camera, map_b);
  octomap::OctreeMap reference(no_repair.octree, camera);
  const std::vector<map::KeyFramePtr> keyframes_b = run(*map_b, compacted);
  EXPECT_EQ(compacted.stats().octree_rebuilds, 1u);
  EXPECT_LE(compacted.stats().peak_stored_image_bytes, (n + 1) * full / 16);
  const int band = 2 * no_repair.mask_border_px + 1;
  for (int k = 0; k < n; ++k) {
    auto [bgr, depth, mask] = images(k);
    cv::Mat exclude;
    cv::dilate(mask, exclude, cv::getStructuringElement(cv::MORPH_ELLIPSE, {band, band}));
    reference.integrate({keyframes_b[k]->id(), keyframes_b[k]->T_w_c(), bgr, depth, exclude});
  }
  EXPECT_EQ(compacted.octree()->stats().occupied_leaves, reference.stats().occupied_leaves);
  EXPECT_EQ(compacted.octree()->stats().free_leaves, reference.stats().free_leaves);
}

// A culled keyframe's own pose stops moving when it is culled; after a loop correction it must be
// taken through its parent, as the camera trajectory takes it. Until 2026-11-26 inpainting used
// its frozen pose as a source, and octree rebuilds left it out.
TEST(DenseMapper, ACulledKeyframeMovesWithItsParentInInpaintingAndRebuilds) {
  const camera::PinholeCamera camera = synthetic::tum3_camera();
  // A striped wall at world z = 2 m, seen from (x, 0, 0) looking along +z; `person` adds a
  // nearer red block and returns its mask.
  auto render = [&](double x, bool person) {
    cv::Mat bgr(camera.height, camera.width, CV_8UC3);
    cv::Mat depth(camera.height, camera.width, CV_32FC1, cv::Scalar(2.0f));
    cv::Mat mask = cv::Mat::zeros(camera.height, camera.width, CV_8UC1);
    for (int v = 0; v < camera.height; ++v) {
      for (int u = 0; u < camera.width; ++u) {
        const double X = x + (u - camera.cx) / camera.fx * 2.0;
        const double Y = (v - camera.cy) / camera.fy * 2.0;
        bgr.at<cv::Vec3b>(v, u) =
            cv::Vec3b(cv::saturate_cast<std::uint8_t>(128 + 100 * std::sin(40 * X)),
                      cv::saturate_cast<std::uint8_t>(128 + 100 * std::cos(23 * Y)),
                      cv::saturate_cast<std::uint8_t>(128 + 60 * std::sin(11 * X + 7 * Y)));
      }
    }
    if (person) {
      const cv::Rect block(250, 150, 120, 180);
      mask(block).setTo(255);
      bgr(block).setTo(cv::Scalar(0, 0, 255));
      depth(block).setTo(1.0f);
    }
    return std::make_tuple(bgr, depth, mask);
  };
  auto pose_at = [](double x) { return SE3(Mat3d::Identity(), Vec3d(x, 0.0, 0.0)); };
  // True camera centres (the corrected map): A 0.0, B 0.25, C 0.12. Before the loop correction,
  // which moves the map by 8 cm, A and B were at -0.08 and 0.17.
  const double shift = 0.08;
  struct Outcome {
    long filled = 0;
    std::size_t scans = 0;
    std::size_t occupied = 0;
    cv::Mat repaired;
  };
  auto run = [&](bool cull_b) {
    const std::string dir =
        (std::filesystem::temp_directory_path() / ("ddl_dense_culled_" + std::to_string(cull_b)))
            .string();
    std::filesystem::remove_all(dir);
    std::filesystem::create_directories(dir);
    auto map = std::make_shared<map::Map>();
    DenseMapperConfig config;
    config.mask_border_px = 0;
    config.save_inpainted_dir = dir;
    DenseMapper dense(config, camera, map);
    auto add = [&](double x_before) {
      auto kf = std::make_shared<map::KeyFrame>(map->next_keyframe_id(), x_before,
                                                std::make_shared<map::FrameFeatures>(),
                                                pose_at(x_before).inverse());
      map->add_keyframe(kf);
      return kf;
    };
    const map::KeyFramePtr a = add(0.0 - shift);
    const auto [a_bgr, a_depth, a_mask] = render(0.0, false);
    dense.submit({a, a_bgr, a_depth, a_mask});
    const map::KeyFramePtr b = add(0.25 - shift);
    b->set_parent(a);
    const auto [b_bgr, b_depth, b_mask] = render(0.25, false);
    dense.submit({b, b_bgr, b_depth, b_mask});
    if (cull_b) {
      EXPECT_TRUE(b->set_bad());
      map->erase_culled_keyframe(b);
    }
    // The loop correction moves the map's keyframes; a culled one is not in the map any more.
    a->set_T_c_w(pose_at(0.0).inverse());
    if (!cull_b) b->set_T_c_w(pose_at(0.25).inverse());
    map->notify_big_change();
    const map::KeyFramePtr c = add(0.12);
    const auto [c_bgr, c_depth, c_mask] = render(0.12, true);
    dense.submit({c, c_bgr, c_depth, c_mask});
    dense.finish();
    Outcome out;
    out.filled = dense.stats().filled_pixels;
    out.scans = dense.octree()->stats().scans_integrated;
    out.occupied = dense.octree()->stats().occupied_leaves;
    out.repaired = cv::imread(dir + "/" + fmt::format("{:.6f}", 0.12) + "_rgb.png");
    std::filesystem::remove_all(dir);
    return out;
  };
  const Outcome live = run(false);
  const Outcome culled = run(true);
  ASSERT_FALSE(live.repaired.empty());
  ASSERT_FALSE(culled.repaired.empty());
  EXPECT_GT(live.filled, 15000);
  EXPECT_EQ(culled.filled, live.filled);
  EXPECT_EQ(culled.scans, live.scans) << "the rebuild leaves the culled keyframe out";
  EXPECT_EQ(culled.occupied, live.occupied);
  cv::Mat difference;
  cv::absdiff(culled.repaired, live.repaired, difference);
  double max_difference = 0.0;
  cv::minMaxLoc(difference.reshape(1), nullptr, &max_difference);
  EXPECT_LE(max_difference, 1.0) << "the culled keyframe was used at its frozen pose";
}

}  // namespace
}  // namespace ddl::pipeline

namespace ddl::pipeline {
namespace {

/// Mean x of the octree's occupied leaves (world frame).
double mean_occupied_x(const octomap::OctreeMap& octree) {
  double sum = 0.0;
  std::size_t n = 0;
  const auto& tree = octree.tree();
  for (auto it = tree.begin_leafs(), end = tree.end_leafs(); it != end; ++it) {
    if (!tree.isNodeOccupied(*it)) continue;
    sum += it.getX();
    ++n;
  }
  return n == 0 ? 0.0 : sum / static_cast<double>(n);
}

// A map file keeps the dense stage's scans (map::DenseScan), so that a later run on the loaded
// map builds the octree of the run that made it, and grows it. A culled keyframe's scan is
// anchored to its parent, which is in the file, and follows it when a later run moves it.
TEST(DenseMapper, ScansSavedWithAMapRebuildItsOctreeInALaterRun) {
  const camera::PinholeCamera camera = synthetic::tum3_camera();
  const auto pose_at = [](double x) { return SE3(Mat3d::Identity(), Vec3d(x, 0.0, 0.0)); };
  const auto images = [&](int k) {
    cv::Mat bgr(camera.height, camera.width, CV_8UC3, cv::Scalar(40 + 50 * k, 80, 120));
    cv::Mat depth(camera.height, camera.width, CV_32FC1, cv::Scalar(2.0f + 0.2f * k));
    return std::make_pair(bgr, depth);
  };
  DenseMapperConfig config;
  config.inpainting_enabled = false;
  const std::filesystem::path dir =
      std::filesystem::path(::testing::TempDir()) / "dense_mapper_scans";
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);

  // The first run: A at x = 0, B at 0.25 (culled later, parent A), C at 0.5.
  std::vector<map::DenseScan> scans;
  std::size_t first_occupied = 0;
  {
    auto map = std::make_shared<map::Map>();
    DenseMapper dense(config, camera, map);
    std::vector<map::KeyFramePtr> kfs;
    for (int k = 0; k < 3; ++k) {
      auto kf = std::make_shared<map::KeyFrame>(map->next_keyframe_id(), k,
                                                std::make_shared<map::FrameFeatures>(),
                                                pose_at(0.25 * k).inverse());
      map->add_keyframe(kf);
      if (k > 0) kf->set_parent(kfs.front());
      kfs.push_back(kf);
      const auto [bgr, depth] = images(k);
      dense.submit({kf, bgr, depth, cv::Mat()});
    }
    EXPECT_THROW(dense.dense_scans(), Error);  // before finish()
    ASSERT_TRUE(kfs[1]->set_bad());
    map->erase_culled_keyframe(kfs[1]);
    dense.finish();
    scans = dense.dense_scans();
    first_occupied = dense.octree()->stats().occupied_leaves;
    dense.octree()->write_ot((dir / "first.ot").string());
    ASSERT_EQ(scans.size(), 3u);
    EXPECT_EQ(scans[1].anchor, kfs[0]->id()) << "the culled keyframe's scan hangs on its parent";
    EXPECT_LT((scans[1].T_anchor_c.translation() - Vec3d(0.25, 0.0, 0.0)).norm(), 1e-12);
    EXPECT_EQ(scans[2].anchor, kfs[2]->id());
    EXPECT_LT(scans[2].T_anchor_c.translation().norm(), 1e-12);
    EXPECT_EQ(scans[0].pixel_step, config.octree.pixel_stride);
    EXPECT_EQ(scans[0].bgr.cols, (camera.width + 3) / 4);
  }
  ASSERT_GT(first_occupied, 100u);

  // A later run on the loaded map (A and C; B was culled): the same octree before any keyframe of
  // its own, and the scans follow their anchors when they move.
  const auto later = [&](double move_a_m, const std::string& ot) {
    auto map = std::make_shared<map::Map>();
    for (const int k : {0, 2}) {
      map->add_keyframe(std::make_shared<map::KeyFrame>(static_cast<map::KeyFrameId>(k), k,
                                                        std::make_shared<map::FrameFeatures>(),
                                                        pose_at(0.25 * k).inverse()));
    }
    DenseMapper dense(config, camera, map);
    dense.preload(scans);
    map->keyframe(0)->set_T_c_w(pose_at(move_a_m).inverse());
    dense.finish();
    EXPECT_EQ(dense.stats().scans_loaded, 3u);
    dense.octree()->write_ot((dir / ot).string());
    return std::make_pair(dense.octree()->stats().occupied_leaves,
                          mean_occupied_x(*dense.octree()));
  };
  const auto [occupied, x_mean] = later(0.0, "later.ot");
  EXPECT_EQ(occupied, first_occupied);
  std::ifstream a(dir / "first.ot", std::ios::binary);
  std::ifstream b(dir / "later.ot", std::ios::binary);
  const std::string first_bytes{std::istreambuf_iterator<char>(a), {}};
  const std::string later_bytes{std::istreambuf_iterator<char>(b), {}};
  EXPECT_TRUE(first_bytes == later_bytes) << "the later run's octree differs from the first's";
  // A moved by 1 m: its scan and the culled B's move with it, C's stays (2 of 3 equal-sized walls).
  const auto [moved_occupied, moved_x_mean] = later(1.0, "moved.ot");
  EXPECT_GT(moved_x_mean - x_mean, 0.4);
  EXPECT_LT(moved_x_mean - x_mean, 0.9);
  std::filesystem::remove_all(dir);
}

// Loaded scans go into the octree only: the run's own keyframes are repaired from its own
// keyframes, and a scan whose stride the octree cannot take is a configuration error.
TEST(DenseMapper, LoadedScansAreNoInpaintingSourcesAndMustFitTheStride) {
  const camera::PinholeCamera camera = synthetic::tum3_camera();
  auto map = std::make_shared<map::Map>();
  auto anchor = std::make_shared<map::KeyFrame>(map->next_keyframe_id(), 0,
                                                std::make_shared<map::FrameFeatures>(), SE3());
  map->add_keyframe(anchor);
  map::DenseScan scan;
  scan.anchor = anchor->id();
  scan.pixel_step = 1;  // full resolution: subsampled on preload
  scan.bgr = cv::Mat(camera.height, camera.width, CV_8UC3, cv::Scalar(10, 200, 10));
  scan.depth_m = cv::Mat(camera.height, camera.width, CV_32FC1, cv::Scalar(2.0f));
  {
    DenseMapperConfig config;
    config.mask_border_px = 0;
    config.octree.pixel_stride = 1;  // the loaded scan stays at full resolution, as a source is
    DenseMapper dense(config, camera, map);
    dense.preload({scan});
    // A keyframe at the same pose with a person in front of the wall: the loaded scan saw the
    // wall behind it, but is no source, so nothing is filled.
    auto kf = std::make_shared<map::KeyFrame>(map->next_keyframe_id(), 1,
                                              std::make_shared<map::FrameFeatures>(), SE3());
    map->add_keyframe(kf);
    cv::Mat bgr(camera.height, camera.width, CV_8UC3, cv::Scalar(10, 200, 10));
    cv::Mat depth(camera.height, camera.width, CV_32FC1, cv::Scalar(2.0f));
    cv::Mat mask = cv::Mat::zeros(camera.height, camera.width, CV_8UC1);
    mask(cv::Rect(250, 150, 120, 180)).setTo(255);
    depth.setTo(1.0f, mask);
    bgr.setTo(cv::Scalar(0, 0, 255), mask);
    dense.submit({kf, bgr, depth, mask});
    EXPECT_THROW(dense.preload({scan}), Error);  // after a submit()
    dense.finish();
    EXPECT_EQ(dense.stats().scans_loaded, 1u);
    EXPECT_GT(dense.stats().masked_pixels, 20000);
    EXPECT_EQ(dense.stats().filled_pixels, 0);
    EXPECT_EQ(dense.octree()->stats().scans_integrated, 2u);
  }
  DenseMapperConfig config;
  DenseMapper dense(config, camera, map);
  scan.pixel_step = 2;
  scan.bgr = cv::Mat(camera.height / 2, camera.width / 2, CV_8UC3, cv::Scalar(10, 200, 10));
  scan.depth_m = cv::Mat(camera.height / 2, camera.width / 2, CV_32FC1, cv::Scalar(2.0f));
  EXPECT_THROW(dense.preload({scan}), ConfigError);
  scan.pixel_step = 4;
  scan.anchor = 99;
  EXPECT_THROW(dense.preload({scan}), Error);  // an anchor the map does not hold
}

}  // namespace
}  // namespace ddl::pipeline
