// The viewer: what the frame and map panels draw where, and the viewer thread's image output.

#include "ddl/viewer/viewer.h"

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <initializer_list>
#include <memory>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/videoio.hpp>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "ddl/core/error.h"
#include "ddl/map/map.h"
#include "ddl/viewer/frame_drawer.h"
#include "ddl/viewer/map_drawer.h"

namespace ddl::viewer {
namespace {

namespace fs = std::filesystem;

ViewFrame grey_frame(std::size_t index = 0) {
  ViewFrame frame;
  frame.index = index;
  frame.rgb = cv::Mat(120, 160, CV_8UC3, cv::Scalar::all(100));
  frame.state = "OK";
  return frame;
}

cv::Vec3b pixel(const cv::Mat& image, int x, int y) { return image.at<cv::Vec3b>(y, x); }

TEST(FrameDrawer, MasksAreTintedByThePartThatMarkedThem) {
  ViewFrame frame = grey_frame();
  frame.cnn = cv::Mat::zeros(120, 160, CV_8UC1);
  frame.geometry = cv::Mat::zeros(120, 160, CV_8UC1);
  frame.memory = cv::Mat::zeros(120, 160, CV_8UC1);
  frame.cnn(cv::Rect(10, 10, 20, 20)).setTo(255);
  frame.geometry(cv::Rect(20, 20, 30, 30)).setTo(255);  // overlaps the CNN mask
  frame.memory(cv::Rect(100, 60, 10, 10)).setTo(255);
  const cv::Mat panel = draw_frame(frame, 0.5);
  ASSERT_EQ(panel.cols, 160);
  ASSERT_EQ(panel.rows, 120 + kStatusBarPx);
  // CNN red: (100, 100, 100) halfway to (0, 0, 255).
  EXPECT_EQ(pixel(panel, 12, 12), cv::Vec3b(50, 50, 178));
  // Where CNN and geometry overlap, the CNN's tint, once.
  EXPECT_EQ(pixel(panel, 25, 25), cv::Vec3b(50, 50, 178));
  // Geometry yellow, memory magenta, elsewhere untouched.
  EXPECT_EQ(pixel(panel, 45, 45), cv::Vec3b(50, 178, 178));
  EXPECT_EQ(pixel(panel, 105, 65), cv::Vec3b(178, 50, 178));
  EXPECT_EQ(pixel(panel, 80, 100), cv::Vec3b(100, 100, 100));
}

TEST(FrameDrawer, KeypointsShowWhetherTheyMatchedAMapPoint) {
  ViewFrame frame = grey_frame();
  frame.keypoints = {{cv::Point2f(40.0f, 60.0f), true}, {cv::Point2f(120.0f, 60.0f), false}};
  const cv::Mat panel = draw_frame(frame);
  EXPECT_EQ(pixel(panel, 40, 60), cv::Vec3b(0, 255, 0));     // matched: green
  EXPECT_EQ(pixel(panel, 120, 60), cv::Vec3b(255, 128, 0));  // unmatched: blue
  EXPECT_EQ(pixel(panel, 80, 60), cv::Vec3b(100, 100, 100));
  // The status line writes into the bar below the image.
  const cv::Mat bar = panel(cv::Rect(0, 120, 160, kStatusBarPx));
  cv::Mat grey;
  cv::extractChannel(bar, grey, 0);
  EXPECT_GT(cv::countNonZero(grey), 20);
}

TEST(FrameDrawer, BadInputIsAnError) {
  ViewFrame frame = grey_frame();
  frame.cnn = cv::Mat::zeros(60, 80, CV_8UC1);
  EXPECT_THROW(draw_frame(frame), std::invalid_argument);
  frame.cnn = cv::Mat::zeros(120, 160, CV_32FC1);
  EXPECT_THROW(draw_frame(frame), std::invalid_argument);
  frame = grey_frame();
  frame.rgb = cv::Mat();
  EXPECT_THROW(draw_frame(frame), std::invalid_argument);
}

// Projects p_w with the view, as draw_map does.
cv::Point2d project(const MapView& view, const Vec3d& p_w) {
  const Vec3d p_v = view.T_v_w * p_w;
  return {view.focal_px * p_v.x() / p_v.z() + 0.5 * view.width,
          view.focal_px * p_v.y() / p_v.z() + 0.5 * view.height};
}

// A 200 x 100 view at the origin looking along +z, focal length 100 px.
MapView small_view() {
  MapView view;
  view.width = 200;
  view.height = 100;
  view.focal_px = 100.0;
  view.T_v_w = SE3();
  return view;
}

// Pixels of a map panel that differ from its background (the colour of its top-left pixel).
int drawn_pixels(const cv::Mat& image) {
  const cv::Mat background(image.size(), CV_8UC3, cv::Scalar(pixel(image, 0, 0)));
  cv::Mat differs;
  cv::absdiff(image, background, differs);
  cv::cvtColor(differs, differs, cv::COLOR_BGR2GRAY);
  return cv::countNonZero(differs);
}

TEST(MapDrawer, LookAtPutsTheTargetOnTheAxisAndDownDown) {
  const Vec3d eye(1.0, -2.0, 0.5), target(0.2, 0.3, 3.0), down(0.0, 0.0, -1.0);
  const SE3 T_v_w = look_at(eye, target, down);
  const Vec3d target_v = T_v_w * target;
  EXPECT_NEAR(target_v.x(), 0.0, 1e-12);
  EXPECT_NEAR(target_v.y(), 0.0, 1e-12);
  EXPECT_NEAR(target_v.z(), (target - eye).norm(), 1e-12);
  // A point below the target (along down) lands below the image centre.
  EXPECT_GT((T_v_w * (target + 0.1 * down)).y(), 0.0);
  EXPECT_THROW(look_at(eye, eye, down), std::invalid_argument);
  EXPECT_THROW(look_at(eye, eye + down, down), std::invalid_argument);
}

TEST(MapDrawer, TheFollowingViewSeesTheCameraFromBehindAndAbove) {
  const SE3 T_w_c(Mat3d(Eigen::AngleAxisd(0.7, Vec3d(0.2, 1.0, 0.1).normalized())),
                  Vec3d(0.5, -0.3, 2.0));
  MapView view;
  view.T_v_w = follow_view(T_w_c, 1.8, 0.7);
  const Vec3d centre_v = view.T_v_w * T_w_c.translation();
  EXPECT_NEAR(centre_v.norm(), std::hypot(1.8, 0.7), 1e-9);
  const cv::Point2d c = project(view, T_w_c.translation());
  EXPECT_NEAR(c.x, 0.5 * view.width, 1e-6);
  EXPECT_NEAR(c.y, 0.5 * view.height, 1e-6);
  // A point 2 m ahead of the camera is seen farther away, above the camera centre (the eye is
  // above it), and not to the side.
  const cv::Point2d ahead = project(view, T_w_c * Vec3d(0.0, 0.0, 2.0));
  EXPECT_NEAR(ahead.x, 0.5 * view.width, 1e-6);
  EXPECT_LT(ahead.y, 0.5 * view.height - 20.0);
  // The camera's right is the view's right.
  EXPECT_GT(project(view, T_w_c * Vec3d(0.5, 0.0, 0.0)).x, 0.5 * view.width + 20.0);
}

TEST(MapDrawer, DrawsPointsWhereTheyProjectAndNothingBehindTheView) {
  const MapView view = small_view();
  MapSnapshot map;
  map.points_w = {Vec3d(0.0, 0.0, 2.0), Vec3d(1.0, 0.0, 2.0), Vec3d(0.0, 0.0, -2.0)};
  const cv::Mat image = draw_map(map, std::nullopt, view);
  const cv::Vec3b background = pixel(image, 10, 10);
  EXPECT_NE(pixel(image, 100, 50), background);  // (0, 0, 2): the centre
  EXPECT_NE(pixel(image, 150, 50), background);  // (1, 0, 2): 100 * 1 / 2 to the right
  EXPECT_EQ(drawn_pixels(image), 2 * 4);         // two 2x2 points; the one behind is not drawn
}

TEST(MapDrawer, TheCurrentCameraIsDrawnAndClippedAtTheNearPlane) {
  MapView view = small_view();
  view.focal_px = 20.0;  // wide, so that a frustum at the eye still lands in the image
  const MapSnapshot empty;
  auto red_pixels = [&](double z) {
    const cv::Mat image = draw_map(empty, SE3(Quatd::Identity(), Vec3d(0.05, 0.0, z)), view);
    std::vector<cv::Mat> channels;
    cv::split(image, channels);
    return cv::countNonZero((channels[2] > 150) & (channels[0] < 100));
  };
  // In front; straddling the near plane (its centre level with the eye, its far corners 4.8 cm
  // ahead: the lines to them are clipped at the plane); wholly behind: nothing.
  EXPECT_GT(red_pixels(1.0), 0);
  EXPECT_GT(red_pixels(0.0), 0);
  EXPECT_EQ(red_pixels(-0.05), 0);
  EXPECT_EQ(drawn_pixels(draw_map(empty, SE3(Quatd::Identity(), Vec3d(0.0, 0.0, -1.0)), view)), 0);
}

// Review finding: a segment crossing the near plane was clipped to a point a rounding error in
// front of or behind the plane, and then dropped in about a quarter of the cases.
TEST(MapDrawer, SegmentsCrossingTheNearPlaneAreDrawnUpToIt) {
  const MapView view = small_view();
  cv::RNG rng(11);
  for (int k = 0; k < 200; ++k) {
    // One end in view (its pixel inside the image), the other behind the view camera.
    const double za = rng.uniform(0.5, 5.0);
    const Vec3d a((rng.uniform(10.0, 190.0) - 100.0) * za / 100.0,
                  (rng.uniform(10.0, 90.0) - 50.0) * za / 100.0, za);
    const Vec3d b(rng.uniform(-2.0, 2.0), rng.uniform(-2.0, 2.0), rng.uniform(-5.0, -0.1));
    MapSnapshot map;
    map.tree_edges_w = {{a, b}};
    EXPECT_GT(drawn_pixels(draw_map(map, std::nullopt, view)), 0) << "segment " << k;
  }
  // Far-off projections (a point just in front of the plane, far to the side) do not overflow.
  MapSnapshot far;
  far.tree_edges_w = {{Vec3d(0.0, 0.0, 1.0), Vec3d(1e9, 1e9, 0.021)}};
  EXPECT_NO_THROW(draw_map(far, std::nullopt, view));
}

TEST(MapDrawer, SnapshotCopiesPointsKeyframesAndTheirTree) {
  map::Map map;
  auto first = std::make_shared<map::KeyFrame>(map.next_keyframe_id(), 0.0,
                                               std::make_shared<map::FrameFeatures>(), SE3());
  map.add_keyframe(first);
  const SE3 T_w_second(Quatd::Identity(), Vec3d(0.3, 0.0, 0.1));
  auto second = std::make_shared<map::KeyFrame>(
      map.next_keyframe_id(), 1.0, std::make_shared<map::FrameFeatures>(), T_w_second.inverse());
  map.add_keyframe(second);
  second->set_parent(first);
  map.add_map_point(
      std::make_shared<map::MapPoint>(map.next_map_point_id(), Vec3d(1.0, 2.0, 3.0), first));
  const MapSnapshot snapshot = snapshot_map(map);
  ASSERT_EQ(snapshot.points_w.size(), 1u);
  EXPECT_EQ(snapshot.points_w[0], Vec3d(1.0, 2.0, 3.0));
  ASSERT_EQ(snapshot.keyframes_T_w_c.size(), 2u);
  EXPECT_NEAR((snapshot.keyframes_T_w_c[1].translation() - Vec3d(0.3, 0.0, 0.1)).norm(), 0.0,
              1e-12);
  ASSERT_EQ(snapshot.tree_edges_w.size(), 1u);
  EXPECT_NEAR((snapshot.tree_edges_w[0].first - Vec3d(0.3, 0.0, 0.1)).norm(), 0.0, 1e-12);
  EXPECT_NEAR(snapshot.tree_edges_w[0].second.norm(), 0.0, 1e-12);
}

class ViewerImages : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ =
        fs::path(::testing::TempDir()) /
        ("viewer_" + std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()));
    fs::remove_all(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  /// Images into dir_, nothing else.
  ViewerConfig image_config(int map_width_px = 640, std::size_t queue_capacity = 4) const {
    ViewerConfig config;
    config.output_dir = dir_.string();
    config.map_width_px = map_width_px;
    config.queue_capacity = queue_capacity;
    return config;
  }
  fs::path dir_;
};

TEST_F(ViewerImages, EveryNthFrameIsWrittenWithBothPanels) {
  auto map = std::make_shared<map::Map>();
  ViewerConfig config = image_config(100, 1);  // queue of 1: show() must wait, never drop
  config.every_n_frames = 3;
  Viewer viewer(config, map);
  for (std::size_t i = 0; i < 10; ++i) {
    ViewFrame frame = grey_frame(i);
    frame.T_w_c = SE3(Quatd::Identity(), Vec3d(0.01 * i, 0.0, 0.0));
    viewer.show(frame);
  }
  viewer.finish();
  EXPECT_EQ(viewer.frames_drawn(), 4u);
  EXPECT_EQ(viewer.frames_dropped(), 0u);
  for (const char* name :
       {"frame_000000.png", "frame_000003.png", "frame_000006.png", "frame_000009.png"}) {
    const cv::Mat image = cv::imread((dir_ / name).string());
    ASSERT_FALSE(image.empty()) << name;
    EXPECT_EQ(image.cols, 160 + 100);
    EXPECT_EQ(image.rows, 120 + kStatusBarPx);
  }
  EXPECT_FALSE(fs::exists(dir_ / "frame_000001.png"));
}

// show() keeps the frame as it was: the caller (whose images other stages share) may reuse or
// change its pixels at once. Twenty frames outpace the drawing thread, so most are drawn after
// the caller has blackened its images.
TEST_F(ViewerImages, AFrameIsDrawnAsItWasWhenItWasShown) {
  auto map = std::make_shared<map::Map>();
  Viewer viewer(image_config(100, 32), map);
  for (std::size_t i = 0; i < 20; ++i) {
    ViewFrame frame = grey_frame(i);
    frame.cnn = cv::Mat::zeros(120, 160, CV_8UC1);
    frame.cnn(cv::Rect(10, 10, 20, 20)).setTo(255);
    cv::Mat rgb = frame.rgb;  // the caller's buffers
    cv::Mat cnn = frame.cnn;
    viewer.show(std::move(frame));
    rgb.setTo(cv::Scalar::all(0));
    cnn.setTo(0);
  }
  viewer.finish();
  ASSERT_EQ(viewer.frames_drawn(), 20u);
  for (std::size_t i = 0; i < 20; ++i) {
    const std::string name = fmt::format("frame_{:06d}.png", i);
    const cv::Mat image = cv::imread((dir_ / name).string());
    ASSERT_FALSE(image.empty()) << name;
    const cv::Vec3b grey = pixel(image, 100, 100);
    const cv::Vec3b tinted = pixel(image, 15, 15);
    EXPECT_EQ(grey, cv::Vec3b(100, 100, 100)) << name;
    EXPECT_NE(tinted, grey) << name << ": the CNN mask is tinted";
  }
}

TEST_F(ViewerImages, TheMapIsDrawnAsItWasWhenTheFrameWasShown) {
  auto map = std::make_shared<map::Map>();
  Viewer viewer(image_config(160), map);
  ViewFrame frame = grey_frame(0);
  frame.T_w_c = SE3();
  viewer.show(frame);
  // Points added after show() must not appear in that frame's image.
  for (int i = 0; i < 50; ++i) {
    map->add_map_point(std::make_shared<map::MapPoint>(map->next_map_point_id(),
                                                       Vec3d(0.02 * i - 0.5, 0.0, 1.0), nullptr));
  }
  frame.index = 1;
  viewer.show(frame);
  viewer.finish();
  const cv::Mat before = cv::imread((dir_ / "frame_000000.png").string());
  const cv::Mat after = cv::imread((dir_ / "frame_000001.png").string());
  ASSERT_FALSE(before.empty());
  ASSERT_FALSE(after.empty());
  const cv::Rect map_panel(160, 0, 160, before.rows);
  const cv::Mat background(map_panel.size(), CV_8UC3, cv::Scalar(pixel(before, 165, 5)));
  // Only the current camera is drawn before; the points too after.
  const double before_diff = cv::norm(before(map_panel), background, cv::NORM_L1);
  const double after_diff = cv::norm(after(map_panel), background, cv::NORM_L1);
  EXPECT_GT(after_diff, before_diff + 50 * 4 * 100);
}

TEST_F(ViewerImages, AnImageThatCannotBeWrittenIsAnErrorOfShowOrFinish) {
  auto map = std::make_shared<map::Map>();
  Viewer viewer(image_config(640, 1), map);
  fs::remove_all(dir_);
  fs::create_directories(dir_.parent_path());
  {
    std::ofstream blocker(dir_);  // a file where the folder was
  }
  bool thrown = false;
  try {
    for (std::size_t i = 0; i < 5; ++i) viewer.show(grey_frame(i));
    viewer.finish();
  } catch (const OutputError& e) {
    thrown = true;
    // The folder the image goes into is named (core/filesystem.h).
    EXPECT_NE(std::string(e.what()).find(dir_.string()), std::string::npos) << e.what();
  }
  EXPECT_TRUE(thrown);
  // The error stays: a caller that goes on is told again instead of losing frames silently.
  EXPECT_THROW(viewer.show(grey_frame(9)), OutputError);
  fs::remove(dir_);
}

TEST_F(ViewerImages, TheVideoHoldsEveryFrameDrawn) {
  auto map = std::make_shared<map::Map>();
  ViewerConfig config;
  config.video_path = (dir_ / "new_folder" / "view.avi").string();  // its folder is created
  config.map_width_px = 100;
  config.every_n_frames = 2;
  config.video_fps = 15.0;
  config.queue_capacity = 1;
  Viewer viewer(config, map);
  for (std::size_t i = 0; i < 9; ++i) viewer.show(grey_frame(i));
  viewer.finish();
  EXPECT_EQ(viewer.frames_drawn(), 5u);
  cv::VideoCapture capture(config.video_path, cv::CAP_OPENCV_MJPEG);
  ASSERT_TRUE(capture.isOpened());
  EXPECT_EQ(capture.get(cv::CAP_PROP_FRAME_WIDTH), 160 + 100);
  EXPECT_EQ(capture.get(cv::CAP_PROP_FRAME_HEIGHT), 120 + kStatusBarPx);
  EXPECT_NEAR(capture.get(cv::CAP_PROP_FPS), 15.0, 1e-6);
  int frames = 0;
  for (cv::Mat image; capture.read(image);) ++frames;
  EXPECT_EQ(frames, 5);
}

TEST_F(ViewerImages, AVideoThatCannotBeWrittenNamesTheFile) {
  ViewerConfig config;
  config.video_path = (dir_ / "view.avi").string();
  fs::create_directories(dir_ / "view.avi");  // a folder where the file should go
  Viewer viewer(config, std::make_shared<map::Map>());
  viewer.show(grey_frame(0));
  try {
    viewer.finish();
    ADD_FAILURE() << "an unwritable video was accepted";
  } catch (const OutputError& e) {
    EXPECT_NE(std::string(e.what()).find("view.avi"), std::string::npos) << e.what();
  }
}

TEST(ViewerConfig, InvalidSettingsNameTheirKey) {
  ViewerConfig config;
  EXPECT_THROW(config.validate(), ConfigError);  // neither window nor images
  config.output_dir = "x";
  config.every_n_frames = 0;
  try {
    config.validate();
    ADD_FAILURE() << "every_n_frames = 0 accepted";
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("every_n_frames"), std::string::npos);
  }
  config.every_n_frames = 1;
  config.video_fps = 0.0;
  EXPECT_THROW(config.validate(), ConfigError);
  config.video_fps = 0.5;  // below OpenCV's Motion-JPEG writer's range (cmd_run clamps to 1)
  EXPECT_THROW(config.validate(), ConfigError);
  config.video_fps = 30.0;
  config.viewpoint_back_m = 0.0;  // straight down the camera's down axis: no image "up"
  EXPECT_THROW(config.validate(), ConfigError);
}

// Sets environment variables for one scope and restores them.
class ScopedEnv {
 public:
  ScopedEnv(std::initializer_list<std::pair<const char*, const char*>> values) {
    for (const auto& [name, value] : values) {
      const char* old = std::getenv(name);
      saved_.push_back({name, old != nullptr, old != nullptr ? old : ""});
      if (value != nullptr) {
        setenv(name, value, 1);
      } else {
        unsetenv(name);
      }
    }
  }
  ~ScopedEnv() {
    for (const Saved& s : saved_) {
      if (s.had) {
        setenv(s.name, s.value.c_str(), 1);
      } else {
        unsetenv(s.name);
      }
    }
  }

 private:
  struct Saved {
    const char* name;
    bool had;
    std::string value;
  };
  std::vector<Saved> saved_;
};

// Review finding: a DISPLAY that is set but cannot be reached made Qt abort the whole process once
// the run had started; the probe finds it first, in a child process.
TEST(Viewer, TheProbeTellsAnUnreachableDisplayFromAUsableOne) {
  {
    const ScopedEnv env{
        {"DISPLAY", ":97"}, {"WAYLAND_DISPLAY", nullptr}, {"QT_QPA_PLATFORM", nullptr}};
    const std::optional<std::string> problem = probe_window_system();
    ASSERT_TRUE(problem.has_value());
    EXPECT_NE(problem->find(":97"), std::string::npos) << *problem;
  }
  {
    const ScopedEnv env{{"QT_QPA_PLATFORM", "offscreen"}};
    const std::optional<std::string> problem = probe_window_system();
    EXPECT_FALSE(problem.has_value()) << *problem;
  }
}

// The window path, drawn off-screen; and the one-window rule (OpenCV's Qt backend serves the
// thread that opened its first window: a second viewer thread waited on the first forever).
TEST(Viewer, TheWindowShowsFramesAndOnlyOneWindowViewerPerProcess) {
  const ScopedEnv env{{"QT_QPA_PLATFORM", "offscreen"}};
  auto map = std::make_shared<map::Map>();
  ViewerConfig config;
  config.window = true;
  config.map_width_px = 100;
  {
    Viewer viewer(config, map);
    for (std::size_t i = 0; i < 3; ++i) viewer.show(grey_frame(i));
    viewer.finish();
    EXPECT_EQ(viewer.frames_drawn() + viewer.frames_dropped(), 3u);
    EXPECT_GE(viewer.frames_drawn(), 1u);
    EXPECT_FALSE(viewer.stop_requested());
  }
  try {
    Viewer second(config, map);
    ADD_FAILURE() << "a second window viewer was accepted";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("one viewer window"), std::string::npos) << e.what();
  }
}

TEST(Viewer, AWindowWithoutADisplayIsAClearError) {
  const ScopedEnv env{
      {"DISPLAY", nullptr}, {"WAYLAND_DISPLAY", nullptr}, {"QT_QPA_PLATFORM", nullptr}};
  ViewerConfig config;
  config.window = true;
  EXPECT_FALSE(display_available());
  EXPECT_TRUE(probe_window_system().has_value());
  try {
    Viewer viewer(config, std::make_shared<map::Map>());
    ADD_FAILURE() << "a window without a display was accepted";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("DISPLAY"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace ddl::viewer
