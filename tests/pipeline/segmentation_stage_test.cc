#include "ddl/pipeline/segmentation_stage.h"

#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <stdexcept>
#include <thread>

namespace ddl::pipeline {
namespace {

/// A source of `count` small frames whose pixels hold their index.
SegmentationStage::FrameSource counting_source(std::size_t count, std::size_t& produced) {
  return [count, &produced]() -> std::optional<io::RgbdFrame> {
    if (produced >= count) return std::nullopt;
    io::RgbdFrame frame;
    frame.index = produced++;
    frame.rgb = cv::Mat(4, 4, CV_8UC3, cv::Scalar::all(static_cast<double>(frame.index)));
    return frame;
  };
}

/// "CNN": the mask holds the frame's index; takes a little time so the consumer overtakes it.
CnnMask index_mask(const io::RgbdFrame& frame) {
  std::this_thread::sleep_for(std::chrono::milliseconds(1));
  CnnMask out;
  out.mask = cv::Mat(4, 4, CV_8UC1, cv::Scalar(static_cast<double>(frame.index)));
  out.elapsed_ms = 1.0;
  return out;
}

TEST(SegmentationStage, DeliversEveryFrameInOrderWithItsOwnMask) {
  std::size_t produced = 0;
  SegmentationStage stage(counting_source(40, produced), index_mask, 2);
  for (std::size_t k = 0; k < 40; ++k) {
    std::optional<SegmentedFrame> item = stage.next();
    ASSERT_TRUE(item) << "frame " << k;
    EXPECT_EQ(item->frame.index, k);
    EXPECT_EQ(item->cnn.mask.at<std::uint8_t>(0, 0), k);
    EXPECT_EQ(item->frame.rgb.at<cv::Vec3b>(3, 3)[0], k);
  }
  EXPECT_FALSE(stage.next());
  EXPECT_FALSE(stage.next());
}

TEST(SegmentationStage, RunsAheadOfTheConsumerByItsCapacity) {
  std::size_t produced = 0;
  std::atomic<std::size_t> segmented{0};
  SegmentationStage stage(
      counting_source(100, produced),
      [&](const io::RgbdFrame& f) {
        ++segmented;
        return index_mask(f);
      },
      3);
  // Without a consumer the worker fills the queue (3) and holds one more frame at its push.
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(10);
  while (segmented.load() < 4 && std::chrono::steady_clock::now() < deadline) {
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  EXPECT_EQ(segmented.load(), 4u);
  std::this_thread::sleep_for(std::chrono::milliseconds(20));
  EXPECT_EQ(segmented.load(), 4u);
}  // the destructor closes the queue while the worker is blocked in push() and joins it

// Live input: a camera whose frame advances while tracking is busy. The worker must take the
// frame that is newest once tracking has room, not one it took, and segmented, while tracking was
// still busy (that frame would be handed on stale after a slow tracking step).
TEST(SegmentationStage, LiveInputTakesTheNewestFrameOnceThereIsRoom) {
  std::atomic<std::size_t> camera_frame{0};  // the frame the camera delivers now
  std::atomic<std::size_t> taken{0};
  SegmentationStage stage(
      [&]() -> std::optional<io::RgbdFrame> {
        ++taken;
        io::RgbdFrame frame;
        frame.index = camera_frame.load();
        frame.rgb = cv::Mat(4, 4, CV_8UC3, cv::Scalar::all(0));
        return frame;
      },
      index_mask, 1, /*take_when_room=*/true);
  // The first frame fills the queue; nothing else is taken while tracking holds no frame.
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(10);
  while (taken.load() < 1 && std::chrono::steady_clock::now() < deadline) {
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  std::this_thread::sleep_for(std::chrono::milliseconds(50));
  EXPECT_EQ(taken.load(), 1u);
  // A slow tracking step: the camera moves on to frame 7 before tracking asks for more.
  camera_frame = 7;
  std::optional<SegmentedFrame> first = stage.next();
  ASSERT_TRUE(first);
  EXPECT_EQ(first->frame.index, 0u);
  std::optional<SegmentedFrame> second = stage.next();
  ASSERT_TRUE(second);
  EXPECT_EQ(second->frame.index, 7u) << "a frame taken before there was room was handed on";
  EXPECT_EQ(second->cnn.mask.at<std::uint8_t>(0, 0), 7);
}

TEST(SegmentationStage, CnnErrorArrivesAtItsFrameAndEndsTheStage) {
  std::size_t produced = 0;
  SegmentationStage stage(counting_source(10, produced), [](const io::RgbdFrame& f) {
    if (f.index == 3) throw std::runtime_error("inference failed");
    return index_mask(f);
  });
  for (std::size_t k = 0; k < 3; ++k) {
    std::optional<SegmentedFrame> item = stage.next();
    ASSERT_TRUE(item);
    EXPECT_EQ(item->frame.index, k);
  }
  EXPECT_THROW(stage.next(), std::runtime_error);
  EXPECT_FALSE(stage.next());
  EXPECT_EQ(produced, 4u);  // nothing read after the failing frame
}

TEST(SegmentationStage, SourceErrorArrivesAtItsFrame) {
  std::size_t produced = 0;
  auto source = counting_source(10, produced);
  SegmentationStage stage(
      [&]() -> std::optional<io::RgbdFrame> {
        if (produced == 2) throw std::runtime_error("unreadable image");
        return source();
      },
      index_mask);
  EXPECT_TRUE(stage.next());
  EXPECT_TRUE(stage.next());
  EXPECT_THROW(stage.next(), std::runtime_error);
  EXPECT_FALSE(stage.next());
}

}  // namespace
}  // namespace ddl::pipeline
