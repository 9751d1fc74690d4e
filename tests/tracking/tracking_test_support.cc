#include "tracking_test_support.h"

#include <cmath>
#include <opencv2/imgproc.hpp>

#include "ddl/features/orb_extractor.h"
#include "ddl/vocabulary/vocabulary_training.h"

namespace ddl::tracking::testing {

camera::PinholeCamera test_camera() {
  camera::PinholeCamera camera;
  camera.name = "test";
  camera.width = 640;
  camera.height = 480;
  camera.fx = 535.4;
  camera.fy = 539.2;
  camera.cx = 320.1;
  camera.cy = 247.6;
  return camera;
}

const SyntheticRoom& room() {
  static const SyntheticRoom instance(7);
  return instance;
}

const RenderedSequence& room_sequence() {
  static const RenderedSequence sequence = [] {
    RenderedSequence s;
    s.T_w_c = smooth_trajectory(40);
    const camera::PinholeCamera camera = test_camera();
    for (std::size_t k = 0; k < s.T_w_c.size(); ++k) {
      s.frames.push_back(room().render(camera, s.T_w_c[k], k, 1000.0 + k / 30.0, 1.0));
    }
    return s;
  }();
  return sequence;
}

std::shared_ptr<const vocabulary::Vocabulary> room_vocabulary() {
  static const std::shared_ptr<const vocabulary::Vocabulary> vocabulary = [] {
    // Training views differ from the test sequence's poses (turned further, shifted back).
    features::OrbExtractor extractor(features::OrbExtractorConfig{});
    std::vector<cv::Mat> descriptors;
    const camera::PinholeCamera camera = test_camera();
    for (int k = 0; k < 8; ++k) {
      const double yaw = (-20.0 + 5.0 * k) * M_PI / 180.0;
      const SE3 T_w_c(so3_exp(Vec3d(0.0, yaw, 0.0)), Vec3d(0.1 * (k % 3) - 0.1, 0.0, -0.3));
      const io::RgbdFrame frame = room().render(camera, T_w_c, 1000 + k, 0.0);
      cv::Mat grey;
      cv::cvtColor(frame.rgb, grey, cv::COLOR_BGR2GRAY);
      descriptors.push_back(extractor.extract(grey).descriptors);
    }
    vocabulary::VocabularyConfig config;
    config.branching = 10;
    config.levels = 4;
    config.seed = 3;
    return std::make_shared<const vocabulary::Vocabulary>(
        vocabulary::train_vocabulary(descriptors, config));
  }();
  return vocabulary;
}

TrackerConfig test_tracker_config() {
  TrackerConfig config;
  config.frame.bow_levels_up = 2;
  return config;
}

void associate_keyframe(const map::KeyFramePtr& keyframe, vocabulary::BowDatabase& database) {
  const auto& features = keyframe->features();
  const std::vector<map::MapPointPtr> points = keyframe->map_points();
  for (std::size_t i = 0; i < points.size(); ++i) {
    const map::MapPointPtr& point = points[i];
    if (!point || point->is_bad() || point->is_in(keyframe->id())) continue;
    point->add_observation(keyframe, i, features.u_right[i] >= 0.0f);
    point->update_normal_and_depth();
    point->compute_distinctive_descriptor();
  }
  keyframe->update_connections();
  database.add(keyframe->id(), keyframe->bow());
}

PoseError pose_error(const SE3& estimate, const SE3& truth) {
  const SE3 delta = truth.inverse() * estimate;
  return {(estimate.translation() - truth.translation()).norm(),
          delta.rotation_angle() * 180.0 / M_PI};
}

// The room's first frame at its ground-truth pose.
Frame first_room_frame_at_truth() {
  const TrackerConfig config = test_tracker_config();
  FrameBuilder builder(test_camera(), config.orb, config.frame);
  Frame frame = builder.build(room_sequence().frames[0], cv::Mat(), 0);
  frame.set_T_c_w(room_sequence().T_w_c[0].inverse());
  return frame;
}

SequenceRun track_sequence(std::size_t count, bool associate, const TrackerConfig& config) {
  SequenceRun run;
  run.map = std::make_shared<map::Map>();
  auto database = std::make_shared<vocabulary::BowDatabase>();
  run.database = database;
  Tracker tracker(config, test_camera(), run.map, room_vocabulary(), database);
  const MappingStatus idle;
  for (std::size_t k = 0; k < count; ++k) {
    TrackingResult r = tracker.track(room_sequence().frames[k], cv::Mat(), idle);
    if (r.new_keyframe) {
      ++run.keyframes_created;
      if (associate) associate_keyframe(r.new_keyframe, *database);
    }
    run.results.push_back(std::move(r));
  }
  run.trajectory = tracker.camera_trajectory();
  return run;
}

}  // namespace ddl::tracking::testing
