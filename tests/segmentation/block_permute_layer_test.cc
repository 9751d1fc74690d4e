// BlockPermuteLayer gives exactly what OpenCV's Permute layer gives: layer by layer on random
// tensors, and for the whole ESPNetv2 network.

#include "ddl/segmentation/block_permute_layer.h"

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
    EXPECT_EQ(block.used_block_path(),
              c.block_path && block_elements >= BlockPermuteLayer::kMinBlockElements);
  }
}

std::string shared_dir() {
  if (const char* env = std::getenv("DDL_SHARED_DIR"); env != nullptr && *env != '\0') return env;
  return DDL_DEFAULT_SHARED_DIR;
}

constexpr char kBasketball[] = "/usr/share/doc/opencv-doc/examples/data/basketball1.png";

cv::Mat network_scores(const fs::path& model, const cv::Mat& blob, bool* used_block_path) {
  cv::dnn::Net net = cv::dnn::readNetFromONNX(model.string());
  net.setPreferableBackend(cv::dnn::DNN_BACKEND_OPENCV);
  net.setPreferableTarget(cv::dnn::DNN_TARGET_CPU);
  net.setInput(blob);
  cv::Mat scores = net.forward().clone();
  *used_block_path = false;
  for (const std::string& name : net.getLayerNames()) {
    const auto* layer = dynamic_cast<const BlockPermuteLayer*>(net.getLayer(name).get());
    if (layer != nullptr && layer->used_block_path()) *used_block_path = true;
  }
  return scores;
}

TEST(BlockPermuteLayer, TheNetworksScoresAreBitForBitOpenCVs) {
  const fs::path model = fs::path(shared_dir()) / SegmenterConfig{}.model_path;
  if (!fs::exists(model)) GTEST_SKIP() << "model not found: " << model;
  if (!fs::exists(kBasketball)) GTEST_SKIP() << "opencv-doc not installed: " << kBasketball;
  const cv::Mat image = cv::imread(kBasketball, cv::IMREAD_COLOR);
  ASSERT_FALSE(image.empty());
  const SegmenterConfig config;
  const cv::Mat blob = cv::dnn::blobFromImage(
      image, 1.0, cv::Size(config.input_width, config.input_height), cv::Scalar(), true, false);

  register_block_permute_layer();
  bool block_used = false;
  const cv::Mat ours = network_scores(model, blob, &block_used);
  EXPECT_TRUE(block_used) << "no Permute layer of the network took the block path";
  // OpenCV's own layer back for one network, then ours again.
  cv::dnn::LayerFactory::unregisterLayer("Permute");
  bool reference_block_used = true;
  const cv::Mat expected = network_scores(model, blob, &reference_block_used);
  cv::dnn::LayerFactory::registerLayer("Permute", BlockPermuteLayer::create);
  EXPECT_FALSE(reference_block_used);
  ASSERT_EQ(ours.total(), expected.total());
  EXPECT_EQ(cv::norm(ours, expected, cv::NORM_INF), 0.0);
}

}  // namespace
}  // namespace ddl::segmentation
