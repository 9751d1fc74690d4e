#include "ddl/io/accelerometer.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "ddl/core/error.h"
#include "test_sequence.h"

namespace ddl::io {
namespace {

using test::TempDir;
using ::testing::HasSubstr;

std::string error_of(const std::string& path) {
  try {
    AccelerometerLog::read(path);
  } catch (const InputError& e) {
    return e.what();
  }
  ADD_FAILURE() << "expected ddl::InputError for " << path;
  return {};
}

TEST(Accelerometer, AnUprightKinectReadsUpAsMinusYInTheCamera) {
  // At rest and upright the Kinect reads +g along its y axis (up); the camera's y points down.
  const auto up = up_in_camera_from_accelerometer(Vec3d(0.0, 9.81, 0.0));
  ASSERT_TRUE(up.has_value());
  EXPECT_NEAR((*up - Vec3d(0, -1, 0)).norm(), 0.0, 1e-12);
  // The Kinect's x points left: a reading along it is up pointing to the image's left (-x).
  const auto left = up_in_camera_from_accelerometer(Vec3d(9.81, 0.0, 0.0));
  ASSERT_TRUE(left.has_value());
  EXPECT_NEAR((*left - Vec3d(-1, 0, 0)).norm(), 0.0, 1e-12);
  // Forward (z) is shared by both frames.
  EXPECT_NEAR(up_in_camera_from_accelerometer(Vec3d(0.0, 0.0, 9.81))->z(), 1.0, 1e-12);
  // A missing sensor's zeros and a knock are not gravity.
  EXPECT_FALSE(up_in_camera_from_accelerometer(Vec3d::Zero()).has_value());
  EXPECT_FALSE(up_in_camera_from_accelerometer(Vec3d(0.0, 30.0, 0.0)).has_value());
}

TEST(Accelerometer, ReadingsAroundAStampAreAveraged) {
  TempDir dir("acc");
  dir.write("accelerometer.txt",
            "# accelerometer data\n# timestamp ax ay az\n"
            "10.00 0 9.81 0\n"
            "10.01 9.81 0 0\n"
            "10.50 0 0 9.81\n");
  const AccelerometerLog log = AccelerometerLog::read(dir.file("accelerometer.txt"));
  ASSERT_EQ(log.samples().size(), 3u);
  // Both of the first two readings lie within 20 ms of 10.005: their mean points half way.
  const auto both = log.up_in_camera_at(10.005);
  ASSERT_TRUE(both.has_value());
  EXPECT_NEAR((*both - Vec3d(-1, -1, 0).normalized()).norm(), 0.0, 1e-9);
  // Only the second one is within 20 ms of 10.025.
  EXPECT_NEAR((*log.up_in_camera_at(10.025) - Vec3d(-1, 0, 0)).norm(), 0.0, 1e-9);
  // No reading within 20 ms of 10.2: no direction.
  EXPECT_FALSE(log.up_in_camera_at(10.2).has_value());
  EXPECT_TRUE(log.up_in_camera_at(10.2, 0.3).has_value());
}

TEST(Accelerometer, MalformedFilesNameTheFileAndLine) {
  TempDir dir("acc_bad");
  dir.write("fields.txt", "# timestamp ax ay az\n1.0 0 9.8 0\n2.0 0 9.8\n");
  const std::string fields = error_of(dir.file("fields.txt"));
  EXPECT_THAT(fields, HasSubstr("fields.txt:3"));
  EXPECT_THAT(fields, HasSubstr("3 fields"));
  dir.write("order.txt", "2.0 0 9.8 0\n1.0 0 9.8 0\n");
  const std::string order = error_of(dir.file("order.txt"));
  EXPECT_THAT(order, HasSubstr("order.txt:2"));
  EXPECT_THAT(order, HasSubstr("before the previous one"));
  dir.write("text.txt", "1.0 0 nine 0\n");
  EXPECT_THAT(error_of(dir.file("text.txt")), HasSubstr("text.txt:1"));
  // strtod reads "nan": a NaN timestamp would pass the order check and break the lookup.
  dir.write("nan.txt", "1.0 0 9.8 0\nnan 0 9.8 0\n");
  const std::string not_finite = error_of(dir.file("nan.txt"));
  EXPECT_THAT(not_finite, HasSubstr("nan.txt:2"));
  EXPECT_THAT(not_finite, HasSubstr("finite"));
  EXPECT_THAT(error_of(dir.file("missing.txt")), HasSubstr("missing.txt"));
}

}  // namespace
}  // namespace ddl::io
