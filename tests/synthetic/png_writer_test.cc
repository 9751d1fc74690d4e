// The generator's PNG encoder: lossless round trip through OpenCV's decoder.

#include "ddl/synthetic/png_writer.h"

#include <gtest/gtest.h>

#include <opencv2/imgcodecs.hpp>

#include "ddl/core/error.h"
#include "ddl/synthetic/random.h"

namespace ddl::synthetic {
namespace {

cv::Mat random_image(int type, std::uint64_t seed) {
  cv::Mat m(37, 53, type);
  Rng rng(seed);
  for (int y = 0; y < m.rows; ++y) {
    auto* p = m.ptr<unsigned char>(y);
    for (std::size_t i = 0; i < m.cols * m.elemSize(); ++i) {
      p[i] = static_cast<unsigned char>(rng.next() & 0xffU);
    }
  }
  return m;
}

TEST(PngWriter, RoundTripsThroughOpenCv) {
  for (int type : {CV_8UC3, CV_8UC1, CV_16UC1}) {
    for (int level : {0, 1, 9}) {
      const cv::Mat image = random_image(type, static_cast<std::uint64_t>(type * 10 + level));
      const auto bytes = encode_png(image, level);
      const cv::Mat decoded = cv::imdecode(bytes, cv::IMREAD_UNCHANGED);
      ASSERT_EQ(decoded.type(), type);
      ASSERT_EQ(decoded.size(), image.size());
      EXPECT_EQ(cv::norm(decoded, image, cv::NORM_INF), 0.0) << "type " << type;
      EXPECT_EQ(encode_png(image, level), bytes) << "deterministic";
    }
  }
  EXPECT_THROW(encode_png(cv::Mat(4, 4, CV_32FC1), 1), Error);
}

}  // namespace
}  // namespace ddl::synthetic
