#include "ddl/io/tum_dataset.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <sys/stat.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <opencv2/imgcodecs.hpp>
#include <stdexcept>
#include <string>
#include <vector>

#include "config_error_check.h"
#include "ddl/core/error.h"
#include "ddl/io/trajectory_io.h"
#include "test_sequence.h"

namespace ddl::io {
namespace {

using test::TempDir;
using test::tiny_camera;
using test::write_sequence;
using ::testing::HasSubstr;

// Runs `fn`, expects a ddl::InputError and returns its message.
template <typename Fn>
std::string input_error_of(Fn&& fn) {
  try {
    fn();
  } catch (const InputError& e) {
    return e.what();
  } catch (const std::exception& e) {
    ADD_FAILURE() << "expected ddl::InputError, got: " << e.what();
    return {};
  }
  ADD_FAILURE() << "expected ddl::InputError, nothing was thrown";
  return {};
}

// ----------------------------------------------------------------------------------------------
// Crafted sequences

TEST(TumDataset, ReadsCraftedSequenceWithDepthInMetres) {
  TempDir dir("seq");
  const auto stamps = write_sequence(dir, 5);
  const TumDataset dataset(dir.path(), tiny_camera());
  ASSERT_EQ(dataset.size(), 5u);
  EXPECT_EQ(dataset.name(), "seq");
  EXPECT_FALSE(dataset.groundtruth_path().has_value());
  EXPECT_DOUBLE_EQ(dataset.timestamp(2), std::stod(stamps[2]));
  EXPECT_THAT(dataset.association_description(), HasSubstr("associate(rgb.txt, depth.txt"));

  const RgbdFrame f = dataset.frame(3);
  EXPECT_EQ(f.index, 3u);
  EXPECT_DOUBLE_EQ(f.timestamp_s, std::stod(stamps[3]));
  ASSERT_EQ(f.rgb.type(), CV_8UC3);
  ASSERT_EQ(f.depth_m.type(), CV_32FC1);
  EXPECT_EQ(f.rgb.at<cv::Vec3b>(5, 7), cv::Vec3b(30, 100, 200));
  for (int u = 0; u < 32; ++u) {
    EXPECT_FLOAT_EQ(f.depth_m.at<float>(11, u), static_cast<float>((5000 + 10 * u) / 5000.0));
  }
  EXPECT_THAT(f.rgb_path, HasSubstr("rgb/" + stamps[3] + ".png"));
}

// accelerometer.txt is read only when asked for: a malformed one then names file and line, and
// does not stop a run that does not use it.
TEST(TumDataset, TheAccelerometerIsReadOnlyWhenAskedFor) {
  TempDir dir("seq");
  write_sequence(dir, 3);
  dir.write("accelerometer.txt", "1000.000 0 9.81 0\n1000.033 0 9.81\n");
  SequenceOptions with_accelerometer;
  with_accelerometer.read_accelerometer = true;
  const std::string error =
      input_error_of([&] { TumDataset(dir.path(), tiny_camera(), with_accelerometer); });
  EXPECT_THAT(error, HasSubstr("accelerometer.txt:2"));
  const TumDataset plain(dir.path(), tiny_camera());
  EXPECT_FALSE(plain.accelerometer().has_value());
  EXPECT_FALSE(plain.frame(0).up_c.has_value());

  dir.write("accelerometer.txt", "1000.000 0 9.81 0\n1000.033 9.81 0 0\n");
  const TumDataset read(dir.path(), tiny_camera(), with_accelerometer);
  ASSERT_TRUE(read.frame(0).up_c.has_value());
  EXPECT_NEAR((*read.frame(0).up_c - Vec3d(0, -1, 0)).norm(), 0.0, 1e-9);
  ASSERT_TRUE(read.frame(1).up_c.has_value());
  EXPECT_NEAR((*read.frame(1).up_c - Vec3d(-1, 0, 0)).norm(), 0.0, 1e-9);
  EXPECT_FALSE(read.frame(2).up_c.has_value());  // no reading within 20 ms of 1000.067
}

TEST(TumDataset, ZeroDepthStaysZeroAndGrayscaleRgbBecomesBgr) {
  TempDir dir("seq");
  write_sequence(dir, 2);
  const TumDataset probe(dir.path(), tiny_camera());
  cv::Mat depth(24, 32, CV_16UC1, cv::Scalar(12345));
  depth(cv::Rect(0, 0, 4, 4)).setTo(0);
  cv::imwrite(probe.pairs()[0].depth_path, depth);
  cv::imwrite(probe.pairs()[0].rgb_path, cv::Mat(24, 32, CV_8UC1, cv::Scalar(77)));

  const RgbdFrame f = TumDataset(dir.path(), tiny_camera()).frame(0);
  EXPECT_EQ(f.depth_m.at<float>(2, 2), 0.0f);
  EXPECT_FLOAT_EQ(f.depth_m.at<float>(10, 10), 12345.0f / 5000.0f);
  ASSERT_EQ(f.rgb.type(), CV_8UC3);
  EXPECT_EQ(f.rgb.at<cv::Vec3b>(3, 3), cv::Vec3b(77, 77, 77));
}

TEST(TumDataset, UsesAssociationsTxtUnlessToldOtherwise) {
  TempDir dir("seq");
  write_sequence(dir, 5);
  const TumDataset computed(dir.path(), tiny_camera());
  const auto& p = computed.pairs();
  // An associations.txt listing frames 0 and 3 only.
  dir.write("associations.txt",
            cv::format("%.6f %s %.6f %s\n%.6f %s %.6f %s\n", p[0].rgb_timestamp_s, "rgb/a.png",
                       p[0].depth_timestamp_s, "depth/a.png", p[3].rgb_timestamp_s, "rgb/b.png",
                       p[3].depth_timestamp_s, "depth/b.png"));
  SequenceOptions no_check;
  no_check.check_files_on_open = false;

  const TumDataset from_file(dir.path(), tiny_camera(), no_check);
  ASSERT_EQ(from_file.size(), 2u);
  EXPECT_EQ(from_file.association_description(), "associations.txt");
  EXPECT_EQ(from_file.pairs()[1].rgb_path, dir.file("rgb/b.png"));
  EXPECT_DOUBLE_EQ(from_file.timestamp(1), p[3].rgb_timestamp_s);

  SequenceOptions timestamps = no_check;
  timestamps.association = AssociationSource::kTimestamps;
  EXPECT_EQ(TumDataset(dir.path(), tiny_camera(), timestamps).size(), 5u);

  // An explicit file elsewhere.
  TempDir other("elsewhere");
  other.write("pairs.txt", cv::format("%.6f rgb/x.png %.6f depth/x.png\n", p[1].rgb_timestamp_s,
                                      p[1].depth_timestamp_s));
  SequenceOptions explicit_file = no_check;
  explicit_file.association = AssociationSource::kFile;
  explicit_file.associations_file = other.file("pairs.txt");
  const TumDataset from_explicit(dir.path(), tiny_camera(), explicit_file);
  ASSERT_EQ(from_explicit.size(), 1u);
  EXPECT_EQ(from_explicit.pairs()[0].rgb_path, dir.file("rgb/x.png"));  // relative to the folder
}

TEST(TumDataset, AssociationFileRequiredButMissing) {
  TempDir dir("seq");
  write_sequence(dir, 2);
  SequenceOptions options;
  options.association = AssociationSource::kFile;
  const std::string msg = input_error_of([&] { TumDataset(dir.path(), tiny_camera(), options); });
  EXPECT_THAT(msg, HasSubstr(dir.file("associations.txt")));
  EXPECT_THAT(msg, HasSubstr("file not found"));
}

TEST(TumDataset, MalformedLineWrongFieldCount) {
  TempDir dir("seq");
  write_sequence(dir, 3);
  dir.write("rgb.txt", "# c\n1000.0 rgb/a.png\n1000.1 rgb/b.png extra\n");
  const std::string msg = input_error_of([&] { TumDataset(dir.path(), tiny_camera()); });
  EXPECT_THAT(msg, HasSubstr(dir.file("rgb.txt") + ":3:"));
  EXPECT_THAT(msg, HasSubstr("expected 2 fields 'timestamp path', found 3"));
}

TEST(TumDataset, MalformedLineNonNumericTimestamp) {
  TempDir dir("seq");
  write_sequence(dir, 3);
  dir.write("depth.txt", "1000.0 depth/a.png\n1000.0x3 depth/b.png\n");
  const std::string msg = input_error_of([&] { TumDataset(dir.path(), tiny_camera()); });
  EXPECT_THAT(msg, HasSubstr(dir.file("depth.txt") + ":2:"));
  EXPECT_THAT(msg, HasSubstr("'1000.0x3' is not a number"));
}

TEST(TumDataset, MalformedAssociationsLine) {
  TempDir dir("seq");
  write_sequence(dir, 3);
  dir.write("associations.txt", "1000.0 rgb/a.png 1000.003 depth/a.png\n1000.1 rgb/b.png\n");
  const std::string msg = input_error_of([&] { TumDataset(dir.path(), tiny_camera()); });
  EXPECT_THAT(msg, HasSubstr(dir.file("associations.txt") + ":2:"));
  EXPECT_THAT(msg, HasSubstr("expected 4 fields"));
}

// associate.py pairs each depth image once: an associations.txt that pairs one twice is an error
// naming both lines.
TEST(TumDataset, ADepthImagePairedTwiceIsAnError) {
  TempDir dir("seq");
  write_sequence(dir, 3);
  dir.write("associations.txt",
            "1000.0 rgb/a.png 1000.003 depth/a.png\n1000.1 rgb/b.png 1000.103 depth/b.png\n"
            "1000.2 rgb/c.png 1000.003 depth/a.png\n");
  SequenceOptions lazy;
  lazy.check_files_on_open = false;
  const std::string msg = input_error_of([&] { TumDataset(dir.path(), tiny_camera(), lazy); });
  EXPECT_THAT(msg, HasSubstr(dir.file("associations.txt") + ":3:"));
  EXPECT_THAT(msg, HasSubstr("paired already on line 1"));
}

// A list saved as "UTF-8 with BOM" keeps its first comment a comment.
TEST(TumDataset, AByteOrderMarkBeforeTheFirstCommentIsSkipped) {
  TempDir dir("seq");
  write_sequence(dir, 3);
  std::ifstream in(dir.file("rgb.txt"));
  const std::string text{std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
  dir.write("rgb.txt", "\xEF\xBB\xBF" + text);
  EXPECT_EQ(TumDataset(dir.path(), tiny_camera()).size(), 3u);
}

TEST(TumDataset, EmptyList) {
  TempDir dir("seq");
  write_sequence(dir, 3);
  dir.write("depth.txt", "# depth maps\n# timestamp filename\n\n");
  const std::string msg = input_error_of([&] { TumDataset(dir.path(), tiny_camera()); });
  EXPECT_THAT(msg, HasSubstr(dir.file("depth.txt")));
  EXPECT_THAT(msg, HasSubstr("empty list"));
}

TEST(TumDataset, NonMonotonicTimestamps) {
  TempDir dir("seq");
  write_sequence(dir, 3);
  dir.write("rgb.txt", "1000.0 rgb/a.png\n1000.2 rgb/b.png\n1000.1 rgb/c.png\n");
  const std::string msg = input_error_of([&] { TumDataset(dir.path(), tiny_camera()); });
  EXPECT_THAT(msg, HasSubstr(dir.file("rgb.txt") + ":3:"));
  EXPECT_THAT(msg, HasSubstr("does not increase"));

  dir.write("rgb.txt", "1000.0 rgb/a.png\n1000.0 rgb/b.png\n");  // a repeated stamp
  EXPECT_THAT(input_error_of([&] { TumDataset(dir.path(), tiny_camera()); }),
              HasSubstr(dir.file("rgb.txt") + ":2:"));
}

TEST(TumDataset, NoAssociatedPairs) {
  TempDir dir("seq");
  write_sequence(dir, 3);
  dir.write("depth.txt", "2000.0 depth/a.png\n2000.1 depth/b.png\n");
  const std::string msg = input_error_of([&] { TumDataset(dir.path(), tiny_camera()); });
  EXPECT_THAT(msg, HasSubstr(dir.path()));
  EXPECT_THAT(msg, HasSubstr("no RGB/depth pairs"));
}

TEST(TumDataset, MissingFolder) {
  TempDir dir("seq");
  const std::string msg =
      input_error_of([&] { TumDataset(dir.file("does_not_exist"), tiny_camera()); });
  EXPECT_THAT(msg, HasSubstr(dir.file("does_not_exist")));
  EXPECT_THAT(msg, HasSubstr("not found"));
}

TEST(TumDataset, MissingImageFile) {
  TempDir dir("seq");
  write_sequence(dir, 3);
  const std::string depth_path = TumDataset(dir.path(), tiny_camera()).pairs()[1].depth_path;
  std::filesystem::remove(depth_path);

  // Found when the sequence is opened...
  std::string msg = input_error_of([&] { TumDataset(dir.path(), tiny_camera()); });
  EXPECT_THAT(msg, HasSubstr(depth_path));
  EXPECT_THAT(msg, HasSubstr("depth image not found"));

  // ... or, with that check off, when the frame is loaded.
  SequenceOptions lazy;
  lazy.check_files_on_open = false;
  const TumDataset dataset(dir.path(), tiny_camera(), lazy);
  EXPECT_NO_THROW(dataset.frame(0));
  msg = input_error_of([&] { dataset.frame(1); });
  EXPECT_THAT(msg, HasSubstr(depth_path));
  EXPECT_THAT(msg, HasSubstr("depth image not found"));
}

TEST(TumDataset, CorruptImage) {
  TempDir dir("seq");
  write_sequence(dir, 2);
  const TumDataset dataset(dir.path(), tiny_camera());
  const std::string rgb_path = dataset.pairs()[1].rgb_path;
  std::ofstream(rgb_path, std::ios::binary | std::ios::trunc) << "\x89PNG\r\n\x1a\n garbage";
  const std::string msg = input_error_of([&] { dataset.frame(1); });
  EXPECT_THAT(msg, HasSubstr(rgb_path));
  EXPECT_THAT(msg, HasSubstr("cannot decode RGB image"));
}

// libjpeg decodes a cut-off JPEG without an error (grey rest, a warning without the file's name):
// the reader refuses it by its missing end-of-image marker. The whole file still reads.
TEST(TumDataset, TruncatedJpegIsAnError) {
  TempDir dir("seq");
  write_sequence(dir, 2);
  const TumDataset dataset(dir.path(), tiny_camera());
  const std::string rgb_path = dataset.pairs()[1].rgb_path;
  std::vector<unsigned char> jpeg;
  ASSERT_TRUE(cv::imencode(".jpg", cv::imread(rgb_path), jpeg));
  const auto write = [&](std::size_t bytes) {
    std::ofstream(rgb_path, std::ios::binary | std::ios::trunc)
        .write(reinterpret_cast<const char*>(jpeg.data()), static_cast<std::streamsize>(bytes));
  };
  write(jpeg.size());
  EXPECT_EQ(dataset.frame(1).rgb.size(), cv::Size(32, 24));
  // Bytes after the end-of-image marker (a writer's trailer) are ignored, as decoders do.
  jpeg.insert(jpeg.end(), 200, 0x55);
  write(jpeg.size());
  EXPECT_EQ(dataset.frame(1).rgb.size(), cv::Size(32, 24));
  jpeg.resize(jpeg.size() - 200);
  write(jpeg.size() * 2 / 3);
  const std::string msg = input_error_of([&] { dataset.frame(1); });
  EXPECT_THAT(msg, HasSubstr(rgb_path));
  EXPECT_THAT(msg, HasSubstr("truncated JPEG"));
}

// A FIFO in an image's place would block the reading thread where Ctrl-C cannot reach it.
TEST(TumDataset, AnImageThatIsNoRegularFileIsAnError) {
  TempDir dir("seq");
  write_sequence(dir, 2);
  const std::string depth_path = TumDataset(dir.path(), tiny_camera()).pairs()[1].depth_path;
  std::filesystem::remove(depth_path);
  ASSERT_EQ(mkfifo(depth_path.c_str(), 0600), 0);
  std::string msg = input_error_of([&] { TumDataset(dir.path(), tiny_camera()); });
  EXPECT_THAT(msg, HasSubstr(depth_path));
  EXPECT_THAT(msg, HasSubstr("not a regular file"));
  SequenceOptions lazy;
  lazy.check_files_on_open = false;
  const TumDataset dataset(dir.path(), tiny_camera(), lazy);
  msg = input_error_of([&] { dataset.frame(1); });
  EXPECT_THAT(msg, HasSubstr("not a regular file"));
}

TEST(TumDataset, EightBitDepthIsAnError) {
  TempDir dir("seq");
  write_sequence(dir, 2);
  const TumDataset dataset(dir.path(), tiny_camera());
  const std::string depth_path = dataset.pairs()[0].depth_path;
  cv::imwrite(depth_path, cv::Mat(24, 32, CV_8UC1, cv::Scalar(100)));
  const std::string msg = input_error_of([&] { dataset.frame(0); });
  EXPECT_THAT(msg, HasSubstr(depth_path));
  EXPECT_THAT(msg, HasSubstr("depth must be 16-bit single-channel"));
  EXPECT_THAT(msg, HasSubstr("found 8-bit 1-channel"));
}

TEST(TumDataset, WronglySizedDepth) {
  TempDir dir("seq");
  write_sequence(dir, 2);
  const TumDataset dataset(dir.path(), tiny_camera());
  const std::string depth_path = dataset.pairs()[0].depth_path;
  cv::imwrite(depth_path, cv::Mat(12, 16, CV_16UC1, cv::Scalar(5000)));
  const std::string msg = input_error_of([&] { dataset.frame(0); });
  EXPECT_THAT(msg, HasSubstr(depth_path));
  EXPECT_THAT(msg, HasSubstr("depth image is 16x12 but camera 'tiny' expects 32x24"));
}

TEST(TumDataset, RgbDepthSizeMismatch) {
  TempDir dir("seq");
  write_sequence(dir, 2);
  const TumDataset dataset(dir.path(), tiny_camera());
  const std::string rgb_path = dataset.pairs()[0].rgb_path;
  cv::imwrite(rgb_path, cv::Mat(48, 64, CV_8UC3, cv::Scalar(1, 2, 3)));
  const std::string msg = input_error_of([&] { dataset.frame(0); });
  EXPECT_THAT(msg, HasSubstr(rgb_path));
  EXPECT_THAT(msg, HasSubstr("RGB image is 64x48 but its depth image"));
  EXPECT_THAT(msg, HasSubstr(dataset.pairs()[0].depth_path + " is 32x24"));
}

TEST(TumDataset, MissingGroundTruth) {
  TempDir dir("seq");
  write_sequence(dir, 2);
  EXPECT_FALSE(TumDataset(dir.path(), tiny_camera()).groundtruth_path().has_value());
  const std::string msg = input_error_of([&] { read_tum_trajectory(dir.file("groundtruth.txt")); });
  EXPECT_THAT(msg, HasSubstr(dir.file("groundtruth.txt")));
  EXPECT_THAT(msg, HasSubstr("file not found"));

  dir.write("groundtruth.txt", "# gt\n1000.0 0 0 0 0 0 0 1\n1000.01 0.1 0 0 0 0 0 1\n");
  const TumDataset with_gt(dir.path(), tiny_camera());
  ASSERT_TRUE(with_gt.groundtruth_path().has_value());
  EXPECT_EQ(read_tum_trajectory(*with_gt.groundtruth_path()).size(), 2u);
}

// groundtruth.txt is validated with the frame lists: a malformed line stops the run before it
// starts, not after its last frame.
TEST(TumDataset, AMalformedGroundTruthIsFoundWhenOpened) {
  TempDir dir("seq");
  write_sequence(dir, 2);
  dir.write("groundtruth.txt", "# gt\n1000.0 0 0 0 0 0 0 1\n1000.01 0.1 0 0 0 0 0\n");
  const std::string msg = input_error_of([&] { TumDataset(dir.path(), tiny_camera()); });
  EXPECT_THAT(msg, HasSubstr(dir.file("groundtruth.txt") + ":3"));
  // A run that does not evaluate (run --no-eval) does not depend on the file.
  SequenceOptions no_eval;
  no_eval.check_groundtruth_on_open = false;
  EXPECT_EQ(TumDataset(dir.path(), tiny_camera(), no_eval).size(), 2u);
}

TEST(TumDataset, IndexOutOfRangeAndBadOptions) {
  TempDir dir("seq");
  write_sequence(dir, 2);
  const TumDataset dataset(dir.path(), tiny_camera());
  EXPECT_THROW(dataset.frame(2), std::out_of_range);
  EXPECT_THROW(dataset.timestamp(7), std::out_of_range);

  SequenceOptions bad;
  bad.max_difference_s = -0.02;
  EXPECT_TRUE(test_support::throws_config_error_naming(
      [&] { TumDataset(dir.path(), tiny_camera(), bad); }, "dataset.max_difference"));
  EXPECT_THROW(parse_association_source("sometimes"), ConfigError);
  EXPECT_EQ(parse_association_source("timestamps"), AssociationSource::kTimestamps);
}

TEST(TumDataset, InvalidCameraIsRejected) {
  TempDir dir("seq");
  write_sequence(dir, 2);
  camera::PinholeCamera camera = tiny_camera();
  camera.depth_factor = 0.0;
  EXPECT_TRUE(test_support::throws_config_error_for_key([&] { TumDataset(dir.path(), camera); },
                                                        "camera.depth_factor"));
}

// ----------------------------------------------------------------------------------------------
// The real TUM fr1_rpy sequence from ../shared

std::string fr1_rpy_dir() { return test::shared_dir() + "/data/tum/rgbd_dataset_freiburg1_rpy"; }

camera::PinholeCamera tum1_camera() {
  // The numbers of config/cameras/tum1.yaml (io must not read YAML; config's tests check that
  // file against these values).
  camera::PinholeCamera c;
  c.name = "tum1";
  c.fx = 517.306408;
  c.fy = 516.469215;
  c.cx = 318.643040;
  c.cy = 255.313989;
  c.distortion = {0.262383, -0.953104, -0.005358, 0.002628, 1.163314};
  c.depth_factor = 5000.0;
  return c;
}

#define SKIP_WITHOUT_FR1_RPY()                                         \
  if (!std::filesystem::exists(fr1_rpy_dir() + "/associations.txt")) { \
    GTEST_SKIP() << "TUM fr1_rpy not found at " << fr1_rpy_dir()       \
                 << " (set DDL_SHARED_DIR to the shared data folder)"; \
  }

// The accelerometer's up against the ground truth's (world z up, the motion-capture frame) at the
// frames' stamps. Hand-held motion adds its own acceleration: measured median 4.8 degrees, 90th
// percentile 9.4, largest 20.3 over the 691 frames with a ground-truth pose within 20 ms.
TEST(TumDatasetFr1Rpy, TheAccelerometerGivesUpWithinAFewDegreesOfGroundTruth) {
  SKIP_WITHOUT_FR1_RPY();
  SequenceOptions options;
  options.read_accelerometer = true;
  const TumDataset dataset(fr1_rpy_dir(), tum1_camera(), options);
  ASSERT_TRUE(dataset.accelerometer().has_value());
  // Not asked for, it is not read.
  EXPECT_FALSE(TumDataset(fr1_rpy_dir(), tum1_camera()).accelerometer().has_value());
  const Trajectory truth = read_tum_trajectory(*dataset.groundtruth_path());
  std::vector<double> angles_deg;
  for (const FramePair& pair : dataset.pairs()) {
    const auto up_c = dataset.accelerometer()->up_in_camera_at(pair.rgb_timestamp_s);
    const auto next =
        std::lower_bound(truth.begin(), truth.end(), pair.rgb_timestamp_s,
                         [](const StampedPose& p, double t) { return p.timestamp_s < t; });
    if (!up_c || next == truth.end() || next->timestamp_s - pair.rgb_timestamp_s > 0.02) continue;
    const Vec3d truth_up_c = next->T_w_c().rotation().transpose() * Vec3d::UnitZ();
    angles_deg.push_back(std::acos(std::clamp(up_c->dot(truth_up_c), -1.0, 1.0)) * 180.0 / M_PI);
  }
  ASSERT_GT(angles_deg.size(), 600u);
  std::sort(angles_deg.begin(), angles_deg.end());
  EXPECT_LT(angles_deg[angles_deg.size() / 2], 7.0);
  EXPECT_LT(angles_deg[angles_deg.size() * 9 / 10], 13.0);
}

TEST(TumDatasetFr1Rpy, ShippedAssociationsAndOwnAssociationAgree) {
  SKIP_WITHOUT_FR1_RPY();
  const TumDataset shipped(fr1_rpy_dir(), tum1_camera());
  EXPECT_EQ(shipped.association_description(), "associations.txt");
  ASSERT_EQ(shipped.size(), 694u);
  ASSERT_TRUE(shipped.groundtruth_path().has_value());
  EXPECT_EQ(shipped.name(), "rgbd_dataset_freiburg1_rpy");

  SequenceOptions own_options;
  own_options.association = AssociationSource::kTimestamps;
  const TumDataset own(fr1_rpy_dir(), tum1_camera(), own_options);
  // associations.txt was made by associate.py (max_difference 0.02 s), so our association of
  // rgb.txt (723 frames) and depth.txt (722 frames) must reproduce it pair for pair.
  ASSERT_EQ(own.size(), 694u) << own.association_description();
  for (std::size_t i = 0; i < own.size(); ++i) {
    const FramePair& a = own.pairs()[i];
    const FramePair& b = shipped.pairs()[i];
    ASSERT_EQ(a.rgb_path, b.rgb_path) << "pair " << i;
    ASSERT_EQ(a.depth_path, b.depth_path) << "pair " << i;
    ASSERT_EQ(a.rgb_timestamp_s, b.rgb_timestamp_s) << "pair " << i;
    ASSERT_EQ(a.depth_timestamp_s, b.depth_timestamp_s) << "pair " << i;
  }
}

TEST(TumDatasetFr1Rpy, FrameHasMetricDepthAndIsUndistorted) {
  SKIP_WITHOUT_FR1_RPY();
  const camera::PinholeCamera cam = tum1_camera();
  const TumDataset dataset(fr1_rpy_dir(), cam);
  EXPECT_FALSE(dataset.camera().has_distortion());
  EXPECT_EQ(dataset.camera().fx, cam.fx);

  const RgbdFrame f = dataset.frame(100);
  ASSERT_EQ(f.rgb.size(), cv::Size(640, 480));
  ASSERT_EQ(f.depth_m.type(), CV_32FC1);
  std::vector<float> valid;
  for (int v = 0; v < f.depth_m.rows; ++v) {
    for (int u = 0; u < f.depth_m.cols; ++u) {
      if (f.depth_m.at<float>(v, u) > 0.0f) valid.push_back(f.depth_m.at<float>(v, u));
    }
  }
  ASSERT_GT(valid.size(), 640u * 480u / 2);
  std::nth_element(valid.begin(), valid.begin() + valid.size() / 2, valid.end());
  const float median_m = valid[valid.size() / 2];
  EXPECT_GT(median_m, 0.3f);
  EXPECT_LT(median_m, 5.0f);

  // Undistortion: undistorted pixel (u, v) shows the stored image at the distorted position of
  // its ray (Brown-Conrady, OpenCV order). Depth is sampled by nearest neighbour, so it must be
  // exactly the raw value there / 5000; colour is bilinear, compared within rounding.
  const cv::Mat raw_rgb = cv::imread(f.rgb_path, cv::IMREAD_COLOR);
  const cv::Mat raw_depth = cv::imread(f.depth_path, cv::IMREAD_UNCHANGED);
  ASSERT_EQ(raw_depth.type(), CV_16UC1);
  const auto& k = cam.distortion;
  int depth_checked = 0, depth_moved = 0;
  double rgb_error = 0.0, rgb_error_if_not_undistorted = 0.0;
  int rgb_checked = 0;
  for (int v = 4; v < 480; v += 13) {
    for (int u = 4; u < 640; u += 13) {
      const double x = (u - cam.cx) / cam.fx, y = (v - cam.cy) / cam.fy;
      const double r2 = x * x + y * y;
      const double radial = 1 + k[0] * r2 + k[1] * r2 * r2 + k[4] * r2 * r2 * r2;
      const double xd = x * radial + 2 * k[2] * x * y + k[3] * (r2 + 2 * x * x);
      const double yd = y * radial + k[2] * (r2 + 2 * y * y) + 2 * k[3] * x * y;
      const double ud = cam.fx * xd + cam.cx, vd = cam.fy * yd + cam.cy;
      if (ud < 1 || vd < 1 || ud > 638 || vd > 478) continue;
      // Depth: skip positions too close to a rounding tie.
      if (std::abs(ud - std::floor(ud) - 0.5) > 0.05 &&
          std::abs(vd - std::floor(vd) - 0.5) > 0.05) {
        const int ur = static_cast<int>(std::lround(ud)), vr = static_cast<int>(std::lround(vd));
        EXPECT_FLOAT_EQ(f.depth_m.at<float>(v, u),
                        static_cast<float>(raw_depth.at<uint16_t>(vr, ur) * (1.0 / 5000.0)))
            << "at (" << u << ", " << v << ")";
        ++depth_checked;
        depth_moved += (ur != u || vr != v) ? 1 : 0;
      }
      const int u0 = static_cast<int>(ud), v0 = static_cast<int>(vd);
      const double a = ud - u0, b = vd - v0;
      for (int c = 0; c < 3; ++c) {
        const auto px = [&](int vv, int uu) { return raw_rgb.at<cv::Vec3b>(vv, uu)[c]; };
        const double expected = (1 - a) * (1 - b) * px(v0, u0) + a * (1 - b) * px(v0, u0 + 1) +
                                (1 - a) * b * px(v0 + 1, u0) + a * b * px(v0 + 1, u0 + 1);
        rgb_error += std::abs(f.rgb.at<cv::Vec3b>(v, u)[c] - expected);
        rgb_error_if_not_undistorted += std::abs(raw_rgb.at<cv::Vec3b>(v, u)[c] - expected);
        ++rgb_checked;
      }
    }
  }
  ASSERT_GT(depth_checked, 1000);
  EXPECT_GT(depth_moved, depth_checked / 2);  // the distortion of fr1 moves most pixels
  EXPECT_LT(rgb_error / rgb_checked, 1.0);    // bilinear with OpenCV's 1/32-pixel weights
  EXPECT_GT(rgb_error_if_not_undistorted / rgb_checked, 3.0 * rgb_error / rgb_checked);
  EXPECT_EQ(cv::norm(dataset.source_area(), camera::Undistorter(cam).source_area(), cv::NORM_INF),
            0.0);
}

// The source area holds the pixels whose distorted position lies in the stored image.
TEST(Undistorter, TheSourceAreaIsWhereAPixelHasAStoredPixel) {
  const camera::PinholeCamera cam = tum1_camera();
  const cv::Mat area = camera::Undistorter(cam).source_area();
  ASSERT_EQ(area.type(), CV_8UC1);
  ASSERT_EQ(area.size(), cv::Size(640, 480));
  const auto& k = cam.distortion;
  int inside = 0, outside = 0;
  for (int v = 0; v < 480; ++v) {
    for (int u = 0; u < 640; ++u) {
      const double x = (u - cam.cx) / cam.fx, y = (v - cam.cy) / cam.fy;
      const double r2 = x * x + y * y;
      const double radial = 1 + k[0] * r2 + k[1] * r2 * r2 + k[4] * r2 * r2 * r2;
      const double ud = cam.fx * (x * radial + 2 * k[2] * x * y + k[3] * (r2 + 2 * x * x)) + cam.cx;
      const double vd = cam.fy * (y * radial + k[2] * (r2 + 2 * y * y) + 2 * k[3] * x * y) + cam.cy;
      // Away from the edge's rounding tie (the map is fixed point).
      if (ud > 0.1 && vd > 0.1 && ud < 639.4 && vd < 479.4) {
        EXPECT_EQ(area.at<std::uint8_t>(v, u), 255) << "at (" << u << ", " << v << ")";
        ++inside;
      } else if (ud < -0.6 || vd < -0.6 || ud > 640.1 || vd > 480.1) {
        EXPECT_EQ(area.at<std::uint8_t>(v, u), 0) << "at (" << u << ", " << v << ")";
        ++outside;
      }
    }
  }
  // Exactly the pixels that undistorted depth can fill (the same nearest-neighbour map).
  const cv::Mat ones(480, 640, CV_16UC1, cv::Scalar(1));
  EXPECT_EQ(cv::countNonZero(area != (camera::Undistorter(cam).undistort_depth(ones) > 0)), 0);
  EXPECT_GT(outside, 1000);   // fr1 leaves a margin
  EXPECT_GT(inside, 280000);  // of 307 200; the margin is a few percent
  // Without distortion nothing is undistorted: no area, every pixel is the sensor's.
  EXPECT_TRUE(camera::Undistorter(cam.undistorted()).source_area().empty());
}

}  // namespace
}  // namespace ddl::io
