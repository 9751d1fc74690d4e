#pragma once
// The viewer: draws each shown frame (FrameDrawer panel) beside the map (MapDrawer panel, the
// view following the camera) in its own thread, fed through a bounded queue, and shows the
// result in a window and/or writes it as PNG images and/or a video (docs/viewer.md).
//
// Flow control: with image or video output every shown frame is drawn (show() waits while the queue
// is full) and the map is copied in show(), at the frame it belongs to, so a deterministic run
// gives the same images. With a window only, show() never waits: a frame the viewer has no room for
// is dropped (counted) and the map is copied when the frame is drawn, so the viewer cannot slow
// tracking down.
// The window (OpenCV highgui) needs a display: DISPLAY or WAYLAND_DISPLAY (or QT_QPA_PLATFORM,
// e.g. "offscreen") must be set, otherwise the constructor throws; probe_window_system() checks
// that it can be reached (the CLI calls it before the run starts). One window per process: the
// Qt backend serves the first thread that opened a window. The window is repainted and its keys
// read when a frame is drawn. 'q' or Esc in the window requests a stop (stop_requested()); the
// caller decides what to do with it.
// Errors of the viewer thread (an image that cannot be written) close the queue; every later
// show() rethrows them, and finish() does unless show() did already.
// Thread-safety: show(), finish() and the accessors from one thread (the caller's).

#include <atomic>
#include <cstddef>
#include <exception>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>

#include "ddl/core/bounded_queue.h"
#include "ddl/core/error.h"
#include "ddl/map/map.h"
#include "ddl/viewer/map_drawer.h"
#include "ddl/viewer/view_frame.h"

namespace ddl::viewer {

struct ViewerConfig {
  bool window = false;             // show the views in a window (needs a display)
  std::string output_dir;          // write <output_dir>/frame_<index, 6 digits>.png; empty = none
  std::string video_path;          // write the views as a Motion-JPEG AVI video; empty = none
  double video_fps = 30.0;         // the video's frame rate, 1-1000 (a sequence's rate /
                                   // every_n_frames)
  int every_n_frames = 1;          // draw the frames whose index is a multiple of this
  int map_width_px = 640;          // map panel width; its height is the frame panel's
  double map_focal_px = 420.0;     // focal length of the map panel's view camera
  double viewpoint_back_m = 1.8;   // the view's eye behind the camera (ORB-SLAM2 ViewpointZ)
  double viewpoint_up_m = 0.7;     // ... and above it (ORB-SLAM2 ViewpointY)
  std::size_t queue_capacity = 4;  // frames waiting to be drawn

  /// Throws ConfigError naming the key for a value out of range, and when neither the window nor
  /// an output folder nor a video is asked for.
  void validate() const;
};

/// Whether a window can be opened: DISPLAY, WAYLAND_DISPLAY or QT_QPA_PLATFORM is set. (OpenCV's
/// Qt backend aborts the process when it finds no display, so this is checked first.)
bool display_available();
/// The error for a window asked for without a display.
Error no_display_error();
/// Whether a window can really be opened: display_available(), then a child process opens and
/// closes one (OpenCV's Qt backend aborts the process when the display cannot be reached).
/// std::nullopt when it can, else the reason. Call it before starting threads (it forks).
std::optional<std::string> probe_window_system();

/// One composed view: the frame panel with the map panel to its right.
cv::Mat compose_view(const ViewFrame& frame, const MapSnapshot& map, const ViewerConfig& config);

class Viewer {
 public:
  /// Starts the viewer thread. Throws ConfigError for an invalid config, Error when the window is
  /// asked for without a display, OutputError when the images' or the video's folder cannot be
  /// created.
  Viewer(const ViewerConfig& config, std::shared_ptr<const map::Map> map);
  ~Viewer();
  Viewer(const Viewer&) = delete;
  Viewer& operator=(const Viewer&) = delete;

  /// Hands one frame to the viewer (frames whose index is not a multiple of every_n_frames are
  /// ignored). Rethrows an error of the viewer thread.
  void show(ViewFrame frame);
  /// Draws what is queued, joins the thread, closes the window; rethrows an error of the viewer
  /// thread. Idempotent.
  void finish();

  std::size_t frames_drawn() const { return drawn_.load(); }
  std::size_t frames_dropped() const { return dropped_; }
  /// 'q' or Esc was pressed in the window.
  bool stop_requested() const { return stop_requested_.load(); }

 private:
  struct Item {
    ViewFrame frame;
    std::optional<MapSnapshot> map;  // copied in show() when every frame is drawn
  };
  void run();
  void rethrow_error();
  void check_error();  // rethrow_error() for show(), remembering that the error was thrown

  ViewerConfig config_;
  std::shared_ptr<const map::Map> map_;
  bool lossless_ = false;
  BoundedQueue<Item> queue_;
  std::thread thread_;
  std::atomic<std::size_t> drawn_{0};
  std::size_t dropped_ = 0;
  std::atomic<bool> stop_requested_{false};
  std::mutex error_mutex_;
  std::exception_ptr error_;
  bool finished_ = false;
  bool error_thrown_ = false;  // show() threw the viewer thread's error already
};

}  // namespace ddl::viewer
