#pragma once
// Dynamic RGB-D benchmark sequences with exact ground truth, written in the TUM RGB-D layout.
//
// Two kinds of source produce frames:
//   - synthetic rooms (SequenceConfig::background_dir empty): the room of scene.h rendered by our
//     renderer along a camera motion (motion.h), with people (people.h) and optionally a movable
//     box;
//   - composite (background_dir = a TUM sequence): the real frames, with real people photos
//     rendered into them at 3-D positions using the sequence's ground-truth poses, drawn only
//     where nearer than the real depth.
//
// Ground-truth conventions (docs/synthetic.md):
//   dynamic_mask   255 where a dynamic entity is visible: a person, or the movable object from the
//                  moment it starts moving on (while carried and after it was put down elsewhere).
//   background     the same frame rendered without any entity that is dynamic in that frame (no
//                  people; no movable object once it has started moving; before that it is part of
//                  the static scene). Same per-pixel sensor noise as the main frame, so outside the
//                  mask the background RGB equals the frame byte for byte, and its depth equals the
//                  frame's depth outside the mask dilated by 2 px (edge dropouts next to people).
//
// Determinism: a frame is a pure function of (config, index); no time, no thread-order effects.

#include <atomic>
#include <cstdint>
#include <functional>
#include <memory>
#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "ddl/camera/pinhole_camera.h"
#include "ddl/core/se3.h"
#include "ddl/io/accelerometer.h"
#include "ddl/io/trajectory_io.h"
#include "ddl/synthetic/depth_model.h"
#include "ddl/synthetic/motion.h"

namespace ddl::synthetic {

enum class PeopleScenario {
  kNone,        // static scene (controls)
  kWalking,     // two people walking all the time (TUM fr3 walking_*)
  kSitting,     // two people seated at the desk, small head/arm motion (TUM fr3 sitting_*)
  kDeskPerson,  // one person enters late and then moves little (TUM fr2 desk_with_person)
};
std::string to_string(PeopleScenario scenario);
PeopleScenario parse_people_scenario(const std::string& text, const std::string& key = "people");

/// An axis-aligned box in the world frame (bounds included).
struct WorldBox {
  Vec3d min_w = Vec3d::Zero();
  Vec3d max_w = Vec3d::Zero();
  bool contains(const Vec3d& p_w) const {
    return (p_w.array() >= min_w.array()).all() && (p_w.array() <= max_w.array()).all();
  }
};

/// Generic photos without people or animals that Debian's opencv-doc package ships, used as
/// posters by default (docs/synthetic.md lists them and their licence). Missing files are skipped
/// by the room builder (procedural posters instead).
std::vector<std::string> default_poster_images();

/// TUM freiburg3 intrinsics (no distortion), 640x480, 30 Hz, depth factor 5000.
camera::PinholeCamera tum3_camera();
/// TUM freiburg1 intrinsics with its distortion (the fr1 images are distorted).
camera::PinholeCamera tum1_camera();

struct SequenceConfig {
  std::string name = "syn_custom";  // sequence name (folder name in a suite)
  int frames = 900;                 // number of frames (composite: at most this many, <= 0 = all)
  std::uint64_t seed = 1;           // everything random derives from it
  MotionType motion = MotionType::kXyz;  // synthetic rooms: camera motion
  /// Loop motion: turns around the room over the whole sequence. 1 = the last pose is the first;
  /// more = the end of the sequence revisits the start (loop detection needs several keyframes
  /// in the revisited place).
  double loop_turns = 1.0;
  PeopleScenario people = PeopleScenario::kNone;  // who is in the scene
  bool moving_object = false;           // a box on the desk is picked up and put down elsewhere
  double object_move_start_s = 12.0;    // when the box starts moving
  double object_move_duration_s = 1.0;  // how long the carry takes
  camera::PinholeCamera camera = tum3_camera();  // synthetic rooms: the rendered camera
  DepthNoiseConfig depth;                        // Kinect-like depth model
  double rgb_noise_sigma = 1.5;                  // sensor noise on the colour images, 8-bit levels
  double start_stamp_s = 1341840000.0;           // timestamp of frame 0 (synthetic rooms)
  double depth_stamp_jitter_s = 0.006;  // depth stamp = rgb stamp + uniform(-j, j), like a Kinect
  std::string people_dir;               // CCP-layout photo folder; empty or missing: silhouettes
  std::vector<std::string> poster_images;  // photos for posters; missing: procedural posters
  std::string background_dir;  // composite: a TUM sequence folder; empty: synthetic room
  camera::PinholeCamera background_camera = tum1_camera();  // composite: camera of that sequence
  double walker_distance_near_m = 1.3;  // composite: distance of the near walker's line
  double walker_distance_far_m = 1.9;   // composite: distance of the far walker's line
  /// Composite: boxes (world frame) around what the real sequence shows of an a-priori dynamic
  /// class that is not part of the dynamic truth, such as a person sitting in the background.
  /// Real pixels whose measured point lies in a box, grown by void_grow_px and minus the dynamic
  /// mask, are void: written to void_mask/ and left out of the mask scores (PASCAL VOC's "void"
  /// label), since a system that masks a person there is right to do so.
  std::vector<WorldBox> void_boxes_w;
  int void_grow_px = 4;  // covers depth dropouts at the outline (hair, edges)

  /// Throws ddl::ConfigError naming the key.
  void validate() const;
  nlohmann::json to_json() const;
};

struct Preset {
  std::string name;
  std::string description;
  SequenceConfig config;  // people_dir, poster_images and background_dir left empty
  /// Composite presets: the background sequence, relative to the shared data folder (the CLI
  /// fills config.background_dir from it); empty for synthetic rooms.
  std::string background_in_shared;
};

/// The benchmark suite: synthetic rows of the paper's Table 1 (walking_*, sitting_*, desk_person),
/// static-room controls for each motion, a loop, and the fr1_rpy composite.
const std::vector<Preset>& presets();
/// Throws ddl::ConfigError (key "preset") listing the valid names.
const Preset& find_preset(const std::string& name);

/// What an entity (person or object) is doing in one frame.
struct EntityState {
  int entity = 0;                    // 1-based entity id (as in FrameData::entity)
  std::string kind;                  // "person" or "object"
  bool visible = false;              // present in the scene at this time (may still be out of view)
  bool dynamic = false;              // counts as dynamic in this frame
  Vec3d position_w = Vec3d::Zero();  // person: feet (billboard bottom centre); object: centre
};

struct FrameData {
  std::size_t index = 0;
  double rgb_stamp_s = 0.0;
  double depth_stamp_s = 0.0;
  SE3 T_w_c;
  cv::Mat rgb;           // CV_8UC3 BGR
  cv::Mat depth_raw;     // CV_16UC1, metres x depth_factor, 0 = no measurement
  cv::Mat dynamic_mask;  // CV_8UC1, 255 where a dynamic entity is visible
  /// CV_8UC1, 255 where a dynamic entity is in the depth image: the composite of a camera with
  /// depth_time_offset_s draws the people into the depth as the sensor saw them at its capture
  /// instant; otherwise the same as dynamic_mask.
  cv::Mat depth_dynamic_mask;
  cv::Mat void_mask;       // CV_8UC1, 255 = not scored (SequenceConfig::void_boxes_w); else empty
  cv::Mat background_rgb;  // CV_8UC3, the frame without dynamic entities
  cv::Mat background_depth_raw;      // CV_16UC1
  cv::Mat depth_exact_m;             // CV_32FC1 rendered depth before the sensor model (0 = none)
  cv::Mat background_depth_exact_m;  // CV_32FC1 (composite: the real depth in metres)
  cv::Mat entity;  // CV_32SC1 per pixel: -1 nothing, 0 static scene, k > 0 entity k
  std::vector<EntityState> entities;
  double dynamic_fraction = 0.0;  // share of pixels in dynamic_mask
};

/// A source of frames. Immutable after construction; render_frame() may be called from any thread.
class SequenceSource {
 public:
  virtual ~SequenceSource() = default;
  virtual const SequenceConfig& config() const = 0;
  /// The camera of the written images (composite: with its distortion).
  virtual const camera::PinholeCamera& camera() const = 0;
  virtual std::size_t frame_count() const = 0;
  virtual FrameData render_frame(std::size_t index) const = 0;
  /// The trajectory written to groundtruth.txt (synthetic: the pose of every frame at its RGB
  /// stamp; composite: the original sequence's ground truth, unchanged).
  virtual io::Trajectory groundtruth() const = 0;
  /// The readings written to accelerometer.txt (io::AccelerometerLog: Kinect axes, x left, y up,
  /// z forward, m/s^2). Synthetic: the specific force of the ground-truth motion (its
  /// acceleration plus gravity) at each frame's RGB stamp, with seeded noise; composite: the
  /// original sequence's readings over its frames, unchanged (none when it has no accelerometer).
  virtual std::vector<io::AccelerometerSample> accelerometer() const = 0;
  /// Scene facts for meta.json: texture sources, people, object, placement.
  virtual nlohmann::json description() const = 0;
};

/// A synthetic room or a composite source, by config.background_dir. Validates the config;
/// throws ddl::ConfigError / ddl::InputError (e.g. a background folder without groundtruth.txt).
std::unique_ptr<SequenceSource> make_sequence_source(const SequenceConfig& config);

struct WriteOptions {
  /// Called after each frame with (frames done, total); from the calling thread.
  std::function<void(std::size_t, std::size_t)> progress;
  const std::atomic<bool>* stop = nullptr;  // when set: finish the frame, write indices, throw
  int png_compression = 1;                  // zlib level of the PNGs (1 = fast)
};

/// Writes the whole sequence into `out_dir`, which must be new, empty, or a sequence an earlier
/// write_sequence wrote (its meta.json names the generator); the entries listed below are then
/// removed first, so no file of the earlier sequence is left beside the new one. Any other
/// folder with content is refused (ddl::InputError naming it): a TUM sequence or a run's
/// outputs are never overwritten. Layout:
///   rgb/ depth/ dynamic_mask/ background/rgb/ background/depth/  (PNG, named <stamp>.png)
///   rgb.txt depth.txt associations.txt groundtruth.txt dynamic_mask.txt
///   accelerometer.txt  (when the source has readings)
///   void_mask/ void_mask.txt  (only when the source has void boxes)
///   background/rgb.txt background/depth.txt background/associations.txt
///   camera.yaml meta.json
/// Throws ddl::InputError naming a file that cannot be written or the refused folder;
/// ddl::Interrupted when stopped
/// (the index files then list the frames written so far).
void write_sequence(const SequenceSource& source, const std::string& out_dir,
                    const WriteOptions& options = {});

/// Timestamp formatting used for file names and lists (TUM style, 6 decimals).
std::string format_stamp(double stamp_s);

}  // namespace ddl::synthetic
