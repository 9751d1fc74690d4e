#pragma once
// Pixel-wise semantic segmentation of a-priori dynamic classes (DDL-SLAM section III-B).
// A Segmenter turns a BGR frame into a label image and a dynamic mask (255 where a pixel belongs
// to one of the configured dynamic classes). Backends: OpenCV dnn running an ONNX model
// (ESPNetv2 trained on PASCAL VOC by default), masks precomputed in a folder, and none.
// Thread-safety: segment() may be called from one thread at a time per instance (cv::dnn nets
// keep state); create one instance per thread.

#include <memory>
#include <opencv2/core.hpp>
#include <set>
#include <string>
#include <vector>

#include "ddl/core/error.h"

namespace ddl::segmentation {

/// PASCAL VOC class names, index = label (0 background ... 20 tvmonitor).
const std::vector<std::string>& voc_class_names();
/// The paper's a-priori dynamic VOC classes: aeroplane, bicycle, bird, boat, bus, car, cat, cow,
/// dog, horse, motorbike, person, sheep, train.
std::vector<std::string> default_dynamic_classes();

enum class Backend {
  kOnnx,    // OpenCV dnn + ONNX model file
  kFolder,  // precomputed masks: <folder>/<rgb file stem>.png, non-zero = dynamic
  kNone,    // no segmentation (empty masks)
};

struct SegmenterConfig {
  Backend backend = Backend::kOnnx;
  /// ONNX model; {W}x{H} in the name is not interpreted: input_width/height must match the model.
  /// 320x240 by default: 2.8x cheaper than 512x384 for 0.05 less IoU (docs/dynamics.md, Speed).
  std::string model_path = "models/espnetv2_s2.0_voc_320x240.onnx";  // in shared dir, else cwd
  int input_width = 320;  // network input size in pixels (the ONNX files have fixed sizes; one
                          // trial inference when the model loads checks it)
  int input_height = 240;
  std::vector<std::string> class_names = voc_class_names();              // label index -> name
  std::vector<std::string> dynamic_classes = default_dynamic_classes();  // masked as dynamic
  int num_threads = 1;      // OpenCV threads; cv::setNumThreads is process-wide (docs/dynamics.md)
  std::string mask_folder;  // kFolder: one mask per RGB file (docs/dynamics.md, Backends)
  int dilation_px = 0;      // grow the mask by this many pixels after upsampling
  bool upright = false;     // onnx: turn a rolled frame upright for the network, where the sequence
                            // has an accelerometer (docs/dynamics.md, Upright segmentation)
  double upright_min_roll_deg = 10.0;  // turn only frames rolled by at least this much (0..180)

  /// Throws ddl::ConfigError naming the key ("dynamic.segmentation.<field>", its place in the
  /// settings).
  void validate() const;
};

struct SegmentationResult {
  cv::Mat labels;        // CV_8UC1 class index per pixel (empty for kFolder/kNone)
  cv::Mat dynamic_mask;  // CV_8UC1, 255 = dynamic class, same size as the input image
  double inference_ms = 0.0;
};

class Segmenter {
 public:
  virtual ~Segmenter() = default;
  /// `bgr`: CV_8UC3. `source_path`: the frame's RGB file (used by the folder backend).
  virtual SegmentationResult segment(const cv::Mat& bgr, const std::string& source_path) = 0;
  virtual std::string description() const = 0;
};

/// The configured model file does not exist. Only this error lets the caller fall back to
/// geometry-only operation (dynamic.fallback_without_model); every other problem with the model
/// or the mask folder is an InputError that ends the run.
class ModelNotFoundError : public InputError {
 public:
  using InputError::InputError;
};

/// Creates the configured backend. For kOnnx, a relative `model_path` is looked up in
/// `shared_dir` first, then in the working directory. A missing model file throws
/// ModelNotFoundError naming it (the caller decides whether to fall back to geometry-only
/// operation, with a warning); an invalid model file throws ddl::InputError naming the file and
/// OpenCV's reason; a missing mask folder (kFolder) throws ddl::InputError naming it.
std::unique_ptr<Segmenter> make_segmenter(const SegmenterConfig& config,
                                          const std::string& shared_dir);

/// Label image -> mask of the labels in `dynamic_labels` (255) at the label image's size.
cv::Mat mask_from_labels(const cv::Mat& labels, const std::set<int>& dynamic_labels);

}  // namespace ddl::segmentation
