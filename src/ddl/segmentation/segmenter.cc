#include "ddl/segmentation/segmenter.h"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <filesystem>
#include <opencv2/core/utility.hpp>
#include <opencv2/dnn.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "ddl/core/error.h"
#include "ddl/core/timing.h"
#include "ddl/segmentation/fast_layers.h"

namespace ddl::segmentation {
namespace fs = std::filesystem;

const std::vector<std::string>& voc_class_names() {
  static const std::vector<std::string> kNames = {
      "background", "aeroplane", "bicycle",     "bird",  "boat",        "bottle", "bus",
      "car",        "cat",       "chair",       "cow",   "diningtable", "dog",    "horse",
      "motorbike",  "person",    "pottedplant", "sheep", "sofa",        "train",  "tvmonitor"};
  return kNames;
}

std::vector<std::string> default_dynamic_classes() {
  return {"aeroplane", "bicycle", "bird",  "boat",      "bus",    "car",   "cat",
          "cow",       "dog",     "horse", "motorbike", "person", "sheep", "train"};
}

void SegmenterConfig::validate() const {
  if (backend == Backend::kOnnx) {
    if (model_path.empty()) {
      throw ConfigError::for_key("dynamic.segmentation.model_path", "must name an ONNX file");
    }
    if (input_width < 32 || input_width > 4096 || input_height < 32 || input_height > 4096) {
      throw ConfigError::for_key(
          "dynamic.segmentation.input_width/input_height",
          fmt::format("must be in 32..4096 (got {}x{})", input_width, input_height));
    }
  }
  if (backend == Backend::kFolder && mask_folder.empty()) {
    throw ConfigError::for_key("dynamic.segmentation.mask_folder",
                               "must be set for the folder backend");
  }
  if (class_names.empty()) {
    throw ConfigError::for_key("dynamic.segmentation.class_names", "is empty");
  }
  for (const auto& name : dynamic_classes) {
    if (std::find(class_names.begin(), class_names.end(), name) == class_names.end()) {
      throw ConfigError::for_key("dynamic.segmentation.dynamic_classes",
                                 fmt::format("'{}' is not one of the model's classes", name));
    }
  }
  if (num_threads < 1 || num_threads > 256) {
    throw ConfigError::for_key("dynamic.segmentation.num_threads", "must be in 1..256");
  }
  if (dilation_px < 0 || dilation_px > 50) {
    throw ConfigError::for_key("dynamic.segmentation.dilation_px", "must be in 0..50");
  }
  if (!(upright_min_roll_deg >= 0.0 && upright_min_roll_deg <= 180.0)) {
    throw ConfigError::for_key("dynamic.segmentation.upright_min_roll_deg", "must be in 0..180");
  }
}

cv::Mat mask_from_labels(const cv::Mat& labels, const std::set<int>& dynamic_labels) {
  std::array<std::uint8_t, 256> lut{};
  for (int label : dynamic_labels) {
    if (label >= 0 && label < 256) lut[static_cast<std::size_t>(label)] = 255;
  }
  cv::Mat mask(labels.size(), CV_8UC1);
  for (int r = 0; r < labels.rows; ++r) {
    const auto* in = labels.ptr<std::uint8_t>(r);
    auto* out = mask.ptr<std::uint8_t>(r);
    for (int c = 0; c < labels.cols; ++c) out[c] = lut[in[c]];
  }
  return mask;
}

namespace {

cv::Mat dilate(const cv::Mat& mask, int px) {
  if (px <= 0 || mask.empty()) return mask;
  cv::Mat out;
  const cv::Mat kernel = cv::getStructuringElement(cv::MORPH_ELLIPSE, {2 * px + 1, 2 * px + 1});
  cv::dilate(mask, out, kernel);
  return out;
}

class OnnxSegmenter final : public Segmenter {
 public:
  OnnxSegmenter(const SegmenterConfig& config, std::string model_path)
      : config_(config), model_path_(std::move(model_path)) {
    register_fast_layers();  // same output, faster channel shuffles and resizes
    try {
      net_ = cv::dnn::readNetFromONNX(model_path_);
    } catch (const cv::Exception& e) {
      throw InputError::at(model_path_, fmt::format("not a loadable ONNX model: {}",
                                                    e.err.empty() ? e.what() : e.err));
    }
    if (net_.empty()) throw InputError::at(model_path_, "not a loadable ONNX model (empty net)");
    net_.setPreferableBackend(cv::dnn::DNN_BACKEND_OPENCV);
    net_.setPreferableTarget(cv::dnn::DNN_TARGET_CPU);
    // OpenCV dnn parallelises layers with cv::parallel_for_, whose thread count is process-wide:
    // this also sets it for every other OpenCV call of the process. The default 1 suits the
    // pipeline, which runs segmentation and tracking on threads of their own (docs/dynamics.md).
    cv::setNumThreads(config_.num_threads);
    for (const auto& name : config_.dynamic_classes) {
      const auto it = std::find(config_.class_names.begin(), config_.class_names.end(), name);
      dynamic_labels_.insert(static_cast<int>(it - config_.class_names.begin()));
    }
    check_input_size();
  }

  /// The network's input: `bgr` resized to the input size, as RGB values 0-255 (the model
  /// normalises internally; shared/README.md).
  cv::Mat input_blob(const cv::Mat& bgr) const {
    return cv::dnn::blobFromImage(bgr, 1.0, cv::Size(config_.input_width, config_.input_height),
                                  cv::Scalar(), /*swapRB=*/true, /*crop=*/false);
  }

  /// One inference on a grey image of the configured input size, so that a size the model does
  /// not take (an ONNX export fixes it) is a configuration error before the first frame instead
  /// of an inference error in it.
  void check_input_size() {
    net_.setInput(input_blob(
        cv::Mat(config_.input_height, config_.input_width, CV_8UC3, cv::Scalar::all(128))));
    try {
      net_.forward();
    } catch (const cv::Exception& e) {
      throw ConfigError::for_key(
          "dynamic.segmentation.input_width/input_height",
          fmt::format("the model {} does not take a {}x{} input (ONNX exports fix their input "
                      "size; its file name usually says it): {}",
                      model_path_, config_.input_width, config_.input_height,
                      e.err.empty() ? e.what() : e.err));
    }
  }

  SegmentationResult segment(const cv::Mat& bgr, const std::string&) override {
    if (bgr.empty() || bgr.type() != CV_8UC3) {
      throw Error("segmentation input must be a non-empty CV_8UC3 BGR image");
    }
    Stopwatch watch;
    net_.setInput(input_blob(bgr));
    cv::Mat scores;
    try {
      scores = net_.forward();
    } catch (const cv::Exception& e) {
      throw InputError::at(model_path_, fmt::format("inference failed: {}", e.what()));
    }
    if (scores.dims != 4 || scores.size[1] != static_cast<int>(config_.class_names.size())) {
      throw InputError::at(model_path_, fmt::format("output has {} channels, expected {} classes",
                                                    scores.dims == 4 ? scores.size[1] : -1,
                                                    config_.class_names.size()));
    }
    const int classes = scores.size[1];
    const int h = scores.size[2];
    const int w = scores.size[3];
    cv::Mat labels(h, w, CV_8UC1);
    const float* data = scores.ptr<float>();
    const std::size_t plane = static_cast<std::size_t>(h) * static_cast<std::size_t>(w);
    for (int r = 0; r < h; ++r) {
      auto* out = labels.ptr<std::uint8_t>(r);
      for (int c = 0; c < w; ++c) {
        const std::size_t idx =
            static_cast<std::size_t>(r) * static_cast<std::size_t>(w) + static_cast<std::size_t>(c);
        int best = 0;
        float best_score = data[idx];
        for (int k = 1; k < classes; ++k) {
          const float s = data[static_cast<std::size_t>(k) * plane + idx];
          if (s > best_score) {
            best_score = s;
            best = k;
          }
        }
        out[c] = static_cast<std::uint8_t>(best);
      }
    }
    SegmentationResult result;
    cv::resize(labels, result.labels, bgr.size(), 0, 0, cv::INTER_NEAREST);
    result.dynamic_mask =
        dilate(mask_from_labels(result.labels, dynamic_labels_), config_.dilation_px);
    result.inference_ms = watch.elapsed_ms();
    return result;
  }

  std::string description() const override {
    return fmt::format("onnx:{} {}x{}", model_path_, config_.input_width, config_.input_height);
  }

 private:
  SegmenterConfig config_;
  std::string model_path_;
  cv::dnn::Net net_;
  std::set<int> dynamic_labels_;
};

class FolderSegmenter final : public Segmenter {
 public:
  explicit FolderSegmenter(const SegmenterConfig& config) : config_(config) {
    if (!fs::is_directory(config_.mask_folder)) {
      throw InputError::at(config_.mask_folder, "mask folder not found");
    }
  }

  SegmentationResult segment(const cv::Mat& bgr, const std::string& source_path) override {
    const fs::path mask_path =
        fs::path(config_.mask_folder) / (fs::path(source_path).stem().string() + ".png");
    // Any depth (8- or 16-bit label images): non-zero = dynamic.
    const cv::Mat mask = cv::imread(mask_path.string(), cv::IMREAD_ANYDEPTH);
    if (mask.empty()) throw InputError::at(mask_path.string(), "mask missing or unreadable");
    if (mask.size() != bgr.size()) {
      throw InputError::at(
          mask_path.string(),
          fmt::format("mask is {}x{}, the frame {}x{}", mask.cols, mask.rows, bgr.cols, bgr.rows));
    }
    SegmentationResult result;
    cv::compare(mask, 0, result.dynamic_mask, cv::CMP_GT);
    result.dynamic_mask = dilate(result.dynamic_mask, config_.dilation_px);
    return result;
  }

  std::string description() const override { return "folder:" + config_.mask_folder; }

 private:
  SegmenterConfig config_;
};

class NoSegmenter final : public Segmenter {
 public:
  SegmentationResult segment(const cv::Mat& bgr, const std::string&) override {
    SegmentationResult result;
    result.dynamic_mask = cv::Mat::zeros(bgr.size(), CV_8UC1);
    return result;
  }
  std::string description() const override { return "none"; }
};

}  // namespace

std::unique_ptr<Segmenter> make_segmenter(const SegmenterConfig& config,
                                          const std::string& shared_dir) {
  config.validate();
  switch (config.backend) {
    case Backend::kNone:
      return std::make_unique<NoSegmenter>();
    case Backend::kFolder:
      return std::make_unique<FolderSegmenter>(config);
    case Backend::kOnnx: {
      // Relative paths: the shared folder first (as documented), the working directory second.
      fs::path model(config.model_path);
      if (model.is_relative() && !shared_dir.empty() && fs::exists(fs::path(shared_dir) / model)) {
        model = fs::path(shared_dir) / model;
      }
      if (!fs::exists(model)) {
        throw ModelNotFoundError(
            InputError::at(model.string(), "segmentation model not found").what());
      }
      return std::make_unique<OnnxSegmenter>(config, model.string());
    }
  }
  throw ConfigError::for_key("dynamic.segmentation.backend", "unknown backend");
}

}  // namespace ddl::segmentation
