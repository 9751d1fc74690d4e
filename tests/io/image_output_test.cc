// PNG outputs: written whole and readable, or an OutputError naming the file; the per-frame log
// counts failures instead of stopping the run.

#include "ddl/io/image_output.h"

#include <gtest/gtest.h>
#include <sys/stat.h>

#include <filesystem>
#include <fstream>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <string>

#include "ddl/core/error.h"

namespace ddl::io {
namespace {
namespace fs = std::filesystem;

fs::path fresh_folder(const std::string& name) {
  const fs::path dir = fs::path(::testing::TempDir()) / name;
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

TEST(WritePng, WritesAnImageThatReadsBackTheSame) {
  const fs::path dir = fresh_folder("image_output_write");
  cv::Mat depth(4, 5, CV_16UC1);
  cv::randu(depth, 0, 65535);
  write_png(dir / "sub" / "depth.png", depth, "a depth image");
  const cv::Mat back = cv::imread((dir / "sub" / "depth.png").string(), cv::IMREAD_UNCHANGED);
  ASSERT_EQ(back.type(), CV_16UC1);
  EXPECT_EQ(cv::norm(back, depth, cv::NORM_INF), 0.0);
  EXPECT_FALSE(fs::exists(dir / "sub" / "depth.png.partial"));
}

TEST(WritePng, AnImagePngCannotHoldIsAnOutputErrorNamingTheFile) {
  const fs::path dir = fresh_folder("image_output_bad");
  try {
    write_png(dir / "empty.png", cv::Mat(), "an empty image");
    ADD_FAILURE() << "no error";
  } catch (const OutputError& e) {
    EXPECT_NE(std::string(e.what()).find("empty.png"), std::string::npos) << e.what();
  }
  EXPECT_FALSE(fs::exists(dir / "empty.png"));
}

TEST(WritePng, AFullDeviceIsAnOutputErrorAndStaysADevice) {
  struct stat info {};
  if (stat("/dev/full", &info) != 0 || !S_ISCHR(info.st_mode)) GTEST_SKIP() << "no /dev/full";
  cv::Mat image(64, 64, CV_8UC3);
  cv::randu(image, 0, 255);
  EXPECT_THROW(write_png("/dev/full", image, "a picture"), OutputError);
  ASSERT_EQ(stat("/dev/full", &info), 0);
  EXPECT_TRUE(S_ISCHR(info.st_mode));
}

TEST(ImageOutputLog, CountsTheFailedWritesAndNamesTheFirst) {
  const fs::path dir = fresh_folder("image_output_log");
  fs::create_directories(dir / "b.png");  // a folder in the second picture's place
  fs::create_directories(dir / "c.png");
  ImageOutputLog log("the test pictures");
  const cv::Mat image(3, 3, CV_8UC1, cv::Scalar(7));
  EXPECT_FALSE(log.error().has_value());
  EXPECT_TRUE(log.write_png(dir / "a.png", image));
  EXPECT_FALSE(log.write_png(dir / "b.png", image));
  EXPECT_FALSE(log.write_png(dir / "c.png", image));
  EXPECT_TRUE(log.write_png(dir / "d.png", image));
  ASSERT_TRUE(log.error().has_value());
  const std::string error = *log.error();
  EXPECT_NE(error.find("2 of 4 files of the test pictures could not be written"), std::string::npos)
      << error;
  EXPECT_NE(error.find("b.png"), std::string::npos) << error;
  EXPECT_TRUE(fs::is_regular_file(dir / "d.png"));
}

}  // namespace
}  // namespace ddl::io
