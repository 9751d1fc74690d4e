#include "ddl/viewer/viewer.h"

#include <fmt/format.h>
#include <spdlog/spdlog.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <opencv2/highgui.hpp>
#include <opencv2/videoio.hpp>

#include "ddl/core/error.h"
#include "ddl/core/filesystem.h"
#include "ddl/io/image_output.h"
#include "ddl/viewer/frame_drawer.h"

namespace fs = std::filesystem;

namespace ddl::viewer {
namespace {

constexpr const char* kWindowName = "DDL-SLAM";

}  // namespace

bool display_available() {
  for (const char* name : {"DISPLAY", "WAYLAND_DISPLAY", "QT_QPA_PLATFORM"}) {
    const char* value = std::getenv(name);
    if (value != nullptr && value[0] != '\0') return true;
  }
  return false;
}

std::optional<std::string> probe_window_system() {
  if (!display_available()) return no_display_error().what();
  // OpenCV's Qt backend aborts the process when the display cannot be reached (a stale DISPLAY,
  // QT_QPA_PLATFORM=xcb without an X server), so a child process tries first.
  std::fflush(nullptr);
  const pid_t child = fork();
  if (child < 0) return std::string("cannot test the display: fork failed");
  if (child == 0) {
    try {
      cv::namedWindow("DDL-SLAM display test", cv::WINDOW_AUTOSIZE);
      cv::destroyAllWindows();
    } catch (...) {
      _exit(1);
    }
    _exit(0);
  }
  int status = 0;
  if (waitpid(child, &status, 0) != child)
    return std::string("cannot test the display: waitpid failed");
  if (WIFEXITED(status) && WEXITSTATUS(status) == 0) return std::nullopt;
  const char* display = std::getenv("DISPLAY");
  return fmt::format(
      "the viewer window cannot be opened on this display (DISPLAY='{}'): the window system "
      "refused it (see the messages above); write the views as images with --save-viewer DIR "
      "instead",
      display != nullptr ? display : "");
}

Error no_display_error() {
  return Error(
      "the viewer window needs a display, and none of DISPLAY, WAYLAND_DISPLAY and "
      "QT_QPA_PLATFORM is set (write the views as images with --save-viewer DIR instead)");
}

void ViewerConfig::validate() const {
  if (!window && output_dir.empty() && video_path.empty()) {
    throw ConfigError::for_key("output_dir",
                               "the viewer needs a window, an output folder or a video file");
  }
  if (!(video_fps >= 1.0 && video_fps <= 1000.0)) {  // OpenCV's Motion-JPEG writer's range
    throw ConfigError::for_key("video_fps", "must be in [1, 1000]");
  }
  if (every_n_frames < 1) throw ConfigError::for_key("every_n_frames", "must be >= 1");
  if (map_width_px < 16) throw ConfigError::for_key("map_width_px", "must be >= 16");
  if (!(map_focal_px > 0.0)) throw ConfigError::for_key("map_focal_px", "must be > 0");
  // back = 0 would look straight down the camera's own down axis, which has no image "up".
  if (!(viewpoint_back_m > 0.0)) throw ConfigError::for_key("viewpoint_back_m", "must be > 0");
  if (!(viewpoint_up_m >= 0.0)) throw ConfigError::for_key("viewpoint_up_m", "must be >= 0");
  if (queue_capacity < 1) throw ConfigError::for_key("queue_capacity", "must be >= 1");
}

cv::Mat compose_view(const ViewFrame& frame, const MapSnapshot& map, const ViewerConfig& config) {
  const cv::Mat frame_panel = draw_frame(frame);
  MapView view;
  view.width = config.map_width_px;
  view.height = frame_panel.rows;
  view.focal_px = config.map_focal_px;
  // Without a pose (lost, not initialised) the view stays at the last keyframe, else the origin.
  SE3 anchor_T_w_c;
  if (frame.T_w_c) {
    anchor_T_w_c = *frame.T_w_c;
  } else if (!map.keyframes_T_w_c.empty()) {
    anchor_T_w_c = map.keyframes_T_w_c.back();
  }
  view.T_v_w = follow_view(anchor_T_w_c, config.viewpoint_back_m, config.viewpoint_up_m);
  cv::Mat view_image;
  cv::hconcat(frame_panel, draw_map(map, frame.T_w_c, view), view_image);
  return view_image;
}

Viewer::Viewer(const ViewerConfig& config, std::shared_ptr<const map::Map> map)
    : config_(config),
      map_(std::move(map)),
      lossless_(!config.output_dir.empty() || !config.video_path.empty()),
      queue_(config.queue_capacity) {
  config_.validate();
  if (map_ == nullptr) throw Error("Viewer: no map given");
  if (config_.window) {
    if (!display_available()) throw no_display_error();
    // OpenCV's Qt backend serves the thread that opened its first window, for the life of the
    // process: a second viewer thread would wait on the first one, gone by then.
    static std::atomic<bool> window_taken{false};
    if (window_taken.exchange(true)) {
      throw Error("only one viewer window per process (OpenCV's Qt backend serves one thread)");
    }
  }
  if (!config_.output_dir.empty()) create_folder(config_.output_dir, "the viewer's images");
  const fs::path video_folder = fs::path(config_.video_path).parent_path();
  if (!video_folder.empty()) create_folder(video_folder, "the viewer's video");
  thread_ = std::thread([this] { run(); });
}

Viewer::~Viewer() {
  try {
    finish();
  } catch (const std::exception& e) {
    spdlog::error("viewer: {}", e.what());
  }
}

void Viewer::show(ViewFrame frame) {
  check_error();
  if (finished_) throw Error("Viewer::show after finish()");
  if (frame.index % static_cast<std::size_t>(config_.every_n_frames) != 0) return;
  // The viewer's thread draws from its own pixels: the caller may reuse or change its images
  // once show() returns. It also keeps ThreadSanitizer's view clean: the buffers are shared with
  // other stages (the dense stage keeps the keyframes' images), and the release of the last
  // reference happens inside libopencv_core, whose atomic count TSan cannot see.
  for (cv::Mat* image : {&frame.rgb, &frame.cnn, &frame.geometry, &frame.memory}) {
    *image = image->clone();
  }
  Item item{std::move(frame), std::nullopt};
  if (lossless_) {
    item.map = snapshot_map(*map_);
    if (!queue_.push(std::move(item))) check_error();
  } else if (!queue_.try_push(std::move(item))) {
    ++dropped_;
  }
}

void Viewer::finish() {
  if (finished_) return;
  finished_ = true;
  queue_.close();
  if (thread_.joinable()) thread_.join();
  if (dropped_ > 0) spdlog::info("viewer: {} frames dropped (it fell behind)", dropped_);
  if (!error_thrown_) rethrow_error();
}

void Viewer::check_error() {
  try {
    rethrow_error();
  } catch (...) {
    error_thrown_ = true;  // finish() then does not report it a second time
    throw;
  }
}

void Viewer::rethrow_error() {
  std::lock_guard lock(error_mutex_);
  if (error_) std::rethrow_exception(error_);  // sticky: every later call fails as well
}

void Viewer::run() {
  bool window_open = false;
  cv::VideoWriter video;
  try {
    while (std::optional<Item> item = queue_.pop()) {
      const MapSnapshot map = item->map ? std::move(*item->map) : snapshot_map(*map_);
      const cv::Mat view = compose_view(item->frame, map, config_);
      if (!config_.video_path.empty()) {
        if (!video.isOpened()) {
          // Motion JPEG in AVI: OpenCV writes it without FFmpeg, and every player reads it.
          video.open(config_.video_path, cv::CAP_OPENCV_MJPEG,
                     cv::VideoWriter::fourcc('M', 'J', 'P', 'G'), config_.video_fps, view.size());
          if (!video.isOpened()) {
            throw OutputError::at(config_.video_path, "cannot write the viewer video (.avi)");
          }
        }
        video.write(view);
      }
      if (!config_.output_dir.empty()) {
        const fs::path path =
            fs::path(config_.output_dir) / fmt::format("frame_{:06d}.png", item->frame.index);
        io::write_png(path, view, "the viewer image");
      }
      if (config_.window) {
        if (!window_open) {
          cv::namedWindow(kWindowName, cv::WINDOW_AUTOSIZE);
          window_open = true;
        }
        cv::imshow(kWindowName, view);
        const int key = cv::waitKey(1);
        if (key == 'q' || key == 'Q' || key == 27) stop_requested_ = true;
      }
      ++drawn_;
    }
  } catch (...) {
    {
      std::lock_guard lock(error_mutex_);
      error_ = std::current_exception();
    }
    queue_.close();
  }
  if (window_open) {
    try {
      cv::destroyWindow(kWindowName);
    } catch (const std::exception& e) {
      spdlog::warn("viewer: closing the window failed: {}", e.what());
    } catch (...) {
      spdlog::warn("viewer: closing the window failed");
    }
  }
}

}  // namespace ddl::viewer
