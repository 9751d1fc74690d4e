#pragma once
// Shared helpers of the tracking tests: the camera, a rendered sequence with ground truth, a small
// vocabulary trained on the synthetic room, a minimal stand-in for local mapping, pose errors.

#include <memory>
#include <vector>

#include "ddl/camera/pinhole_camera.h"
#include "ddl/core/se3.h"
#include "ddl/io/rgbd_frame.h"
#include "ddl/io/trajectory_io.h"
#include "ddl/map/keyframe.h"
#include "ddl/map/map.h"
#include "ddl/tracking/frame.h"
#include "ddl/tracking/tracker.h"
#include "ddl/tracking/tracker_config.h"
#include "ddl/vocabulary/bow_database.h"
#include "ddl/vocabulary/vocabulary.h"
#include "synthetic_room.h"

namespace ddl::tracking::testing {

/// TUM fr3-like undistorted 640x480 camera.
camera::PinholeCamera test_camera();

/// Frames rendered along smooth_trajectory(frames), 30 Hz stamps, with ground-truth T_w_c.
struct RenderedSequence {
  std::vector<io::RgbdFrame> frames;
  std::vector<SE3> T_w_c;
};
/// Rendered once per process and cached (rendering is the slow part of these tests).
const RenderedSequence& room_sequence();
const SyntheticRoom& room();

/// Vocabulary (k = 10, L = 4) trained on ORB descriptors of views of the room; cached.
std::shared_ptr<const vocabulary::Vocabulary> room_vocabulary();

/// Tracker settings for the tests (the defaults, BoW direct index 2 levels above the words to
/// suit the 4-level test vocabulary).
TrackerConfig test_tracker_config();

/// What local mapping does first with a new keyframe (ORB-SLAM2 ProcessNewKeyFrame, without
/// culling, triangulation, fusion or BA): the keyframe's matched points get its observation, their
/// descriptor and normal are refreshed, the covisibility links are updated, and the keyframe goes
/// into the BoW database.
void associate_keyframe(const map::KeyFramePtr& keyframe, vocabulary::BowDatabase& database);

/// The room's first frame, features extracted, at its ground-truth pose.
Frame first_room_frame_at_truth();

struct SequenceRun {
  std::vector<TrackingResult> results;
  io::Trajectory trajectory;
  std::shared_ptr<map::Map> map;
  std::shared_ptr<vocabulary::BowDatabase> database;  // filled only with `associate`
  std::size_t keyframes_created = 0;
};

/// Tracks frames [0, count) of the room sequence. With `associate`, each new keyframe goes
/// through the minimal local-mapping stand-in (observations, covisibility, BoW database).
SequenceRun track_sequence(std::size_t count, bool associate, const TrackerConfig& config);

struct PoseError {
  double translation_m = 0.0;
  double rotation_deg = 0.0;
};
/// Error of `estimate` against `truth` (both T_w_c).
PoseError pose_error(const SE3& estimate, const SE3& truth);

}  // namespace ddl::tracking::testing
