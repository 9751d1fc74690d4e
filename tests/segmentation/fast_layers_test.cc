// The faster layers give exactly what OpenCV's own give: BlockPermuteLayer and CornerResizeLayer
// layer by layer on random tensors, and the whole ESPNetv2 network with both.

#include "ddl/segmentation/fast_layers.h"

#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <opencv2/core.hpp>
#include <opencv2/dnn.hpp>
#include <opencv2/dnn/all_layers.hpp>
#include <opencv2/dnn/shape_utils.hpp>
#include <opencv2/imgcodecs.hpp>
#include <string>
#include <vector>

#include "ddl/segmentation/block_permute_layer.h"
#include "ddl/segmentation/corner_resize_layer.h"
#include "ddl/segmentation/segmenter.h"

namespace ddl::segmentation {
namespace {
namespace fs = std::filesystem;

cv::dnn::LayerParams permute_params(const std::vector<int>& order) {
  cv::dnn::LayerParams params;
  params.name = "permute";
  params.type = "Permute";
  params.set("order", cv::dnn::DictValue::arrayInt(order.data(), static_cast<int>(order.size())));
  return params;
}

// Runs one layer standalone as a network would: output shapes, finalize, forward.
cv::Mat run_layer(cv::dnn::Layer& layer, const cv::Mat& input) {
  std::vector<cv::dnn::MatShape> in_shapes{cv::dnn::shape(input)}, out_shapes, internal_shapes;
  layer.getMemoryShapes(in_shapes, 1, out_shapes, internal_shapes);
  std::vector<cv::Mat> inputs{input};
  std::vector<cv::Mat> outputs{cv::Mat(out_shapes[0], CV_32F, cv::Scalar(-1.0f))};
  std::vector<cv::Mat> internals;
  for (const cv::dnn::MatShape& s : internal_shapes) internals.emplace_back(s, CV_32F);
  layer.finalize(inputs, outputs);
  layer.forward(inputs, outputs, internals);
  return outputs[0];
}

struct Case {
  std::vector<int> shape;
  std::vector<int> order;
  bool block_path;  // whether the block path applies
};

TEST(BlockPermuteLayer, GivesExactlyWhatOpenCVsPermuteGives) {
  const std::vector<Case> cases = {
      {{1, 5, 10, 12, 16}, {0, 2, 1, 3, 4}, true},  // ESPNetv2's channel shuffle
      {{3, 4, 5, 6}, {1, 0, 2, 3}, true},           // outer swap, blocks of 30
      {{2, 3, 4, 8}, {2, 0, 1, 3}, true},           // rotation of the outer three, blocks of 8 < 16
      {{2, 3, 40, 5}, {3, 1, 0, 2}, false},         // innermost dimension moves
      {{1, 10, 18, 16}, {0, 1, 3, 2}, false},       // ESPNetv2's last-two transpose
      {{2, 3, 4, 5}, {0, 1, 2, 3}, true},           // identity
  };
  cv::RNG rng(7);
  for (const Case& c : cases) {
    cv::Mat input(c.shape, CV_32F);
    rng.fill(input, cv::RNG::UNIFORM, -10.0, 10.0);
    cv::dnn::LayerParams params = permute_params(c.order);
    BlockPermuteLayer block(params);
    const cv::Mat ours = run_layer(block, input);
    cv::Ptr<cv::dnn::PermuteLayer> reference = cv::dnn::PermuteLayer::create(params);
    const cv::Mat expected = run_layer(*reference, input);
    ASSERT_EQ(ours.dims, expected.dims);
    for (int d = 0; d < ours.dims; ++d) ASSERT_EQ(ours.size[d], expected.size[d]);
    EXPECT_EQ(cv::norm(ours, expected, cv::NORM_INF), 0.0) << "order of " << c.order.size();
    std::size_t block_elements = 1;
    int kept = static_cast<int>(c.order.size());
    while (kept > 0 && c.order[kept - 1] == kept - 1) block_elements *= c.shape[--kept];
    EXPECT_EQ(block.used_own_path(),
              c.block_path && block_elements >= BlockPermuteLayer::kMinBlockElements);
  }
}

std::string shared_dir() {
  if (const char* env = std::getenv("DDL_SHARED_DIR"); env != nullptr && *env != '\0') return env;
  return DDL_DEFAULT_SHARED_DIR;
}

constexpr char kBasketball[] = "/usr/share/doc/opencv-doc/examples/data/basketball1.png";

struct NetworkRun {
  cv::Mat scores;
  bool block_permute_used = false;  // a BlockPermuteLayer took its block path
  bool corner_resize_used = false;  // a CornerResizeLayer took its plane path
};

NetworkRun run_network(const fs::path& model, const cv::Mat& blob) {
  cv::dnn::Net net = cv::dnn::readNetFromONNX(model.string());
  net.setPreferableBackend(cv::dnn::DNN_BACKEND_OPENCV);
  net.setPreferableTarget(cv::dnn::DNN_TARGET_CPU);
  net.setInput(blob);
  NetworkRun run;
  run.scores = net.forward().clone();
  for (const std::string& name : net.getLayerNames()) {
    const cv::Ptr<cv::dnn::Layer> layer = net.getLayer(name);
    if (const auto* p = dynamic_cast<const BlockPermuteLayer*>(layer.get())) {
      run.block_permute_used |= p->used_own_path();
    }
    if (const auto* r = dynamic_cast<const CornerResizeLayer*>(layer.get())) {
      run.corner_resize_used |= r->used_own_path();
    }
  }
  return run;
}

TEST(FastLayers, TheNetworksScoresAreBitForBitOpenCVs) {
  const fs::path model = fs::path(shared_dir()) / SegmenterConfig{}.model_path;
  if (!fs::exists(model)) GTEST_SKIP() << "model not found: " << model;
  if (!fs::exists(kBasketball)) GTEST_SKIP() << "opencv-doc not installed: " << kBasketball;
  const cv::Mat image = cv::imread(kBasketball, cv::IMREAD_COLOR);
  ASSERT_FALSE(image.empty());
  const SegmenterConfig config;
  const cv::Mat blob = cv::dnn::blobFromImage(
      image, 1.0, cv::Size(config.input_width, config.input_height), cv::Scalar(), true, false);

  register_fast_layers();
  const NetworkRun ours = run_network(model, blob);
  EXPECT_TRUE(ours.block_permute_used) << "no Permute layer took the block path";
  EXPECT_TRUE(ours.corner_resize_used) << "no Resize layer took the plane path";
  // OpenCV's own layers back for one network, then ours again.
  cv::dnn::LayerFactory::unregisterLayer("Permute");
  cv::dnn::LayerFactory::unregisterLayer("Resize");
  const NetworkRun expected = run_network(model, blob);
  cv::dnn::LayerFactory::registerLayer("Permute", BlockPermuteLayer::create);
  cv::dnn::LayerFactory::registerLayer("Resize", CornerResizeLayer::create);
  EXPECT_FALSE(expected.block_permute_used || expected.corner_resize_used);
  ASSERT_EQ(ours.scores.total(), expected.scores.total());
  EXPECT_EQ(cv::norm(ours.scores, expected.scores, cv::NORM_INF), 0.0);
}

cv::dnn::LayerParams resize_params(const std::string& interpolation, bool align_corners, int height,
                                   int width) {
  cv::dnn::LayerParams params;
  params.name = "resize";
  params.type = "Resize";
  params.set("interpolation", interpolation);
  params.set("align_corners", align_corners);
  params.set("height", height);
  params.set("width", width);
  return params;
}

TEST(CornerResizeLayer, GivesExactlyWhatOpenCVsResizeGives) {
  struct ResizeCase {
    std::vector<int> shape;
    int height, width;
    std::string interpolation;
    bool align_corners;
    bool plane_path;
  };
  const std::vector<ResizeCase> cases = {
      {{1, 21, 120, 160}, 240, 320, "bilinear", true, true},  // ESPNetv2's last resize
      {{1, 10, 12, 16}, 120, 160, "bilinear", true, true},    // x10, as in its decoder
      {{2, 3, 7, 5}, 13, 11, "bilinear", true, true},         // odd sizes, batch of 2
      {{1, 3, 9, 9}, 5, 4, "bilinear", true, true},           // downscaling
      {{1, 4, 6, 8}, 12, 16, "bilinear", false, false},       // not aligned corners: OpenCV's
      {{1, 4, 6, 8}, 12, 16, "nearest", false, false},        // nearest: OpenCV's
  };
  cv::RNG rng(5);
  for (const ResizeCase& c : cases) {
    cv::Mat input(c.shape, CV_32F);
    rng.fill(input, cv::RNG::UNIFORM, -30.0, 30.0);
    cv::dnn::LayerParams params =
        resize_params(c.interpolation, c.align_corners, c.height, c.width);
    CornerResizeLayer ours_layer(params);
    const cv::Mat ours = run_layer(ours_layer, input);
    cv::Ptr<cv::dnn::ResizeLayer> reference = cv::dnn::ResizeLayer::create(params);
    const cv::Mat expected = run_layer(*reference, input);
    ASSERT_EQ(ours.total(), expected.total());
    EXPECT_EQ(cv::norm(ours, expected, cv::NORM_INF), 0.0)
        << c.interpolation << " " << c.height << "x" << c.width;
    EXPECT_EQ(ours_layer.used_own_path(), c.plane_path) << c.height << "x" << c.width;
  }
}

}  // namespace
}  // namespace ddl::segmentation
