// The faster layers give exactly what OpenCV's own give: BlockPermuteLayer and CornerResizeLayer
// layer by layer on random tensors, and the whole ESPNetv2 network with both.

#include "ddl/segmentation/fast_layers.h"

#include <gtest/gtest.h>

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
#include "shared_data.h"

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

cv::dnn::LayerParams resize_params(const std::string& interpolation, bool align_corners,
                                   bool half_pixel_centers, int height, int width) {
  cv::dnn::LayerParams params;
  params.name = "resize";
  params.type = "Resize";
  params.set("interpolation", interpolation);
  params.set("align_corners", align_corners);
  params.set("half_pixel_centers", half_pixel_centers);
  params.set("height", height);
  params.set("width", width);
  return params;
}

// Runs one layer standalone as a network would: output shapes, finalize, the target set
// afterwards (as Net does), forward. The output starts as a sentinel of the input's type.
cv::Mat run_layer(cv::dnn::Layer& layer, const cv::Mat& input,
                  int target = cv::dnn::DNN_TARGET_CPU) {
  std::vector<cv::dnn::MatShape> in_shapes{cv::dnn::shape(input)}, out_shapes, internal_shapes;
  layer.getMemoryShapes(in_shapes, 1, out_shapes, internal_shapes);
  std::vector<cv::Mat> inputs{input};
  std::vector<cv::Mat> outputs{cv::Mat(out_shapes[0], input.type(), cv::Scalar(0x7777))};
  std::vector<cv::Mat> internals;
  for (const cv::dnn::MatShape& s : internal_shapes) internals.emplace_back(s, input.type());
  layer.finalize(cv::InputArrayOfArrays(inputs), cv::OutputArrayOfArrays(outputs));
  layer.preferableTarget = target;
  layer.forward(inputs, outputs, internals);
  return outputs[0];
}

// Both layers' outputs element by element (any type), as one flat row.
bool identical(const cv::Mat& a, const cv::Mat& b) {
  if (a.type() != b.type() || a.total() != b.total()) return false;
  const cv::Mat flat_a(1, static_cast<int>(a.total() * a.elemSize()), CV_8U, a.data);
  const cv::Mat flat_b(1, static_cast<int>(b.total() * b.elemSize()), CV_8U, b.data);
  return cv::countNonZero(flat_a != flat_b) == 0;
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

// The identity order runs in place in a network (input and output share memory).
TEST(BlockPermuteLayer, TheIdentityInPlaceLeavesTheData) {
  cv::Mat data({2, 3, 4, 5}, CV_32F);
  cv::randu(data, -1.0, 1.0);
  const cv::Mat before = data.clone();
  cv::dnn::LayerParams params = permute_params({0, 1, 2, 3});
  BlockPermuteLayer layer(params);
  std::vector<cv::Mat> inputs{data}, outputs{data}, internals;
  layer.finalize(cv::InputArrayOfArrays(inputs), cv::OutputArrayOfArrays(outputs));
  layer.forward(inputs, outputs, internals);
  EXPECT_TRUE(layer.used_own_path());
  EXPECT_EQ(cv::norm(data, before, cv::NORM_INF), 0.0);
}

// Review finding: on the OpenCL FP16 target the blobs hold half floats (CV_16S); the stand-ins
// handed them to OpenCV's layer without the target, which then wrote nothing.
TEST(FastLayers, OtherTargetsGetOpenCVsLayersResult) {
  cv::Mat permute_input({1, 5, 10, 12, 16}, CV_32F), resize_input({1, 4, 15, 20}, CV_32F);
  cv::randu(permute_input, -5.0, 5.0);
  cv::randu(resize_input, -5.0, 5.0);
  cv::Mat permute_half, resize_half;
  cv::convertFp16(permute_input, permute_half);
  cv::convertFp16(resize_input, resize_half);
  const int fp16 = cv::dnn::DNN_TARGET_OPENCL_FP16;

  cv::dnn::LayerParams permute = permute_params({0, 2, 1, 3, 4});
  BlockPermuteLayer block(permute);
  const cv::Mat ours = run_layer(block, permute_half, fp16);
  EXPECT_FALSE(block.used_own_path());
  EXPECT_TRUE(
      identical(ours, run_layer(*cv::dnn::PermuteLayer::create(permute), permute_half, fp16)));

  cv::dnn::LayerParams resize = resize_params("bilinear", true, false, 30, 40);
  CornerResizeLayer corner(resize);
  const cv::Mat ours_resized = run_layer(corner, resize_half, fp16);
  EXPECT_FALSE(corner.used_own_path());
  EXPECT_TRUE(
      identical(ours_resized, run_layer(*cv::dnn::ResizeLayer::create(resize), resize_half, fp16)));
}

using test_support::shared_dir;
constexpr const char* kBasketball = test_support::kBasketballPhoto;

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

// Runs `f` once with OpenCV's own layers back in the factory, then puts ours back.
template <typename F>
auto with_opencv_layers(F f) {
  cv::dnn::LayerFactory::unregisterLayer("Permute");
  cv::dnn::LayerFactory::unregisterLayer("Resize");
  auto result = f();
  cv::dnn::LayerFactory::registerLayer("Permute", BlockPermuteLayer::create);
  cv::dnn::LayerFactory::registerLayer("Resize", CornerResizeLayer::create);
  return result;
}

TEST(FastLayers, TheNetworksScoresAreBitForBitOpenCVs) {
  if (!fs::exists(kBasketball)) GTEST_SKIP() << "opencv-doc not installed: " << kBasketball;
  const cv::Mat image = cv::imread(kBasketball, cv::IMREAD_COLOR);
  ASSERT_FALSE(image.empty());
  register_fast_layers();
  int models = 0;
  // The default model and the larger ones a user may choose (dynamic.segmentation.model_path).
  for (const cv::Size size : {cv::Size(320, 240), cv::Size(512, 384), cv::Size(640, 480)}) {
    const fs::path model = fs::path(shared_dir()) / "models" /
                           ("espnetv2_s2.0_voc_" + std::to_string(size.width) + "x" +
                            std::to_string(size.height) + ".onnx");
    if (!fs::exists(model)) continue;
    ++models;
    const cv::Mat blob = cv::dnn::blobFromImage(image, 1.0, size, cv::Scalar(), true, false);
    const NetworkRun ours = run_network(model, blob);
    EXPECT_TRUE(ours.block_permute_used) << model << ": no Permute layer took the block path";
    EXPECT_TRUE(ours.corner_resize_used) << model << ": no Resize layer took the plane path";
    const NetworkRun expected = with_opencv_layers([&] { return run_network(model, blob); });
    EXPECT_FALSE(expected.block_permute_used || expected.corner_resize_used);
    ASSERT_EQ(ours.scores.total(), expected.scores.total());
    EXPECT_EQ(cv::norm(ours.scores, expected.scores, cv::NORM_INF), 0.0) << model;
  }
  if (models == 0) GTEST_SKIP() << "no ESPNetv2 model in " << shared_dir();
}

// Review finding: quantization asks each layer for its int8 form; the stand-ins said they had
// none, so a quantized network kept float Permute and Resize layers and scored differently.
TEST(FastLayers, AQuantizedNetworkIsOpenCVs) {
  const fs::path model = fs::path(shared_dir()) / SegmenterConfig{}.model_path;
  if (!fs::exists(model)) GTEST_SKIP() << "model not found: " << model;
  if (!fs::exists(kBasketball)) GTEST_SKIP() << "opencv-doc not installed: " << kBasketball;
  const SegmenterConfig config;
  const cv::Mat blob = cv::dnn::blobFromImage(cv::imread(kBasketball, cv::IMREAD_COLOR), 1.0,
                                              cv::Size(config.input_width, config.input_height),
                                              cv::Scalar(), true, false);
  auto quantized_scores = [&] {
    cv::dnn::Net net = cv::dnn::readNetFromONNX(model.string());
    net.setPreferableBackend(cv::dnn::DNN_BACKEND_OPENCV);
    net.setPreferableTarget(cv::dnn::DNN_TARGET_CPU);
    cv::dnn::Net quantized = net.quantize(std::vector<cv::Mat>{blob}, CV_32F, CV_32F);
    quantized.setInput(blob);
    return quantized.forward().clone();
  };
  register_fast_layers();
  const cv::Mat ours = quantized_scores();
  const cv::Mat expected = with_opencv_layers(quantized_scores);
  ASSERT_EQ(ours.total(), expected.total());
  EXPECT_EQ(cv::norm(ours, expected, cv::NORM_INF), 0.0);
}

TEST(CornerResizeLayer, GivesExactlyWhatOpenCVsResizeGives) {
  struct ResizeCase {
    std::vector<int> shape;
    int height, width;
    std::string interpolation;
    bool align_corners;
    bool half_pixel_centers;
    bool plane_path;
  };
  const std::vector<ResizeCase> cases = {
      {{1, 21, 120, 160}, 240, 320, "bilinear", true, false, true},  // ESPNetv2's last resize
      {{1, 10, 12, 16}, 120, 160, "bilinear", true, false, true},    // x10, as in its decoder
      {{2, 3, 7, 5}, 13, 11, "bilinear", true, false, true},         // odd sizes, batch of 2
      {{1, 3, 9, 9}, 5, 4, "bilinear", true, false, true},           // downscaling
      {{1, 4, 6, 8}, 12, 16, "bilinear", true, true, false},         // half-pixel: OpenCV's
      {{1, 4, 6, 8}, 12, 16, "bilinear", false, false, false},       // not aligned: OpenCV's
      {{1, 4, 6, 8}, 12, 16, "nearest", false, false, false},        // nearest: OpenCV's
  };

  cv::RNG rng(5);
  for (const ResizeCase& c : cases) {
    cv::Mat input(c.shape, CV_32F);
    rng.fill(input, cv::RNG::UNIFORM, -30.0, 30.0);
    cv::dnn::LayerParams params =
        resize_params(c.interpolation, c.align_corners, c.half_pixel_centers, c.height, c.width);
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
