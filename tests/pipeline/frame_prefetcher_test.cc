// FramePrefetcher: every frame in order; paced and live (frames dropped like a camera with a
// one-frame buffer: skipped or replaced, never reordered, the newest kept).

#include "ddl/pipeline/frame_prefetcher.h"

#include <gtest/gtest.h>

#include <chrono>
#include <string>
#include <thread>
#include <vector>

#include "ddl/core/error.h"

namespace ddl::pipeline {
namespace {

// Tiny frames at 30 Hz, made on demand.
class StampDataset final : public io::DatasetReader {
 public:
  explicit StampDataset(std::size_t frames) : frames_(frames) {}
  std::size_t size() const override { return frames_; }
  double timestamp(std::size_t i) const override { return 1000.0 + static_cast<double>(i) / 30.0; }
  io::RgbdFrame frame(std::size_t i) const override {
    io::RgbdFrame f;
    f.index = i;
    f.timestamp_s = timestamp(i);
    f.rgb = cv::Mat(8, 8, CV_8UC3, cv::Scalar::all(0));
    f.depth_m = cv::Mat(8, 8, CV_32F, cv::Scalar(1.0f));
    return f;
  }
  const camera::PinholeCamera& camera() const override { return camera_; }
  std::optional<std::string> groundtruth_path() const override { return std::nullopt; }
  std::string name() const override { return "stamps"; }

 private:
  std::size_t frames_;
  camera::PinholeCamera camera_;
};

std::vector<std::size_t> take_all(FramePrefetcher& prefetcher,
                                  std::chrono::milliseconds work = std::chrono::milliseconds(0)) {
  std::vector<std::size_t> indices;
  while (std::optional<io::RgbdFrame> frame = prefetcher.next()) {
    indices.push_back(frame->index);
    std::this_thread::sleep_for(work);
  }
  return indices;
}

TEST(FramePrefetcher, EveryFrameInOrderUnpacedOrPaced) {
  const StampDataset dataset(12);
  FramePrefetcher unpaced(dataset, 2, 12);
  const std::vector<std::size_t> all = take_all(unpaced);
  ASSERT_EQ(all.size(), 10u);
  for (std::size_t k = 0; k < all.size(); ++k) EXPECT_EQ(all[k], k + 2);

  FramePacer pacer(4.0);
  PrefetchOptions paced;
  paced.pacer = &pacer;
  FramePrefetcher slow_consumer(dataset, 0, 12, paced);
  // A consumer slower than the camera gets every frame all the same, late.
  EXPECT_EQ(take_all(slow_consumer, std::chrono::milliseconds(30)).size(), 12u);
  EXPECT_EQ(slow_consumer.frames_dropped(), 0u);
}

TEST(FramePrefetcher, LiveModeDropsWhatABusyConsumerCannotTakeAndKeepsTheNewest) {
  const StampDataset dataset(30);  // one second at 30 Hz
  FramePacer pacer(1.0);
  PrefetchOptions live;
  live.pacer = &pacer;
  live.drop_late = true;
  FramePrefetcher prefetcher(dataset, 0, 30, live);
  // The consumer needs 100 ms per frame: it can take about one frame in three.
  const std::vector<std::size_t> taken = take_all(prefetcher, std::chrono::milliseconds(100));
  ASSERT_FALSE(taken.empty());
  EXPECT_EQ(taken.size() + prefetcher.frames_dropped(), 30u);
  EXPECT_GE(prefetcher.frames_dropped(), 10u);
  for (std::size_t k = 1; k < taken.size(); ++k) EXPECT_GT(taken[k], taken[k - 1]);
  EXPECT_EQ(taken.back(), 29u);  // the last frame has no successor to replace it
}

// A loading error in live mode is never dropped: it reaches the consumer, naming the file.
TEST(FramePrefetcher, ALoadingErrorInLiveModeReachesTheConsumer) {
  class FailingDataset final : public io::DatasetReader {
   public:
    std::size_t size() const override { return inner_.size(); }
    double timestamp(std::size_t i) const override { return inner_.timestamp(i); }
    io::RgbdFrame frame(std::size_t i) const override {
      if (i == 9) throw InputError::at("rgb/9.png", "cannot decode");  // never skipped: the last
      return inner_.frame(i);
    }
    const camera::PinholeCamera& camera() const override { return inner_.camera(); }
    std::optional<std::string> groundtruth_path() const override { return std::nullopt; }
    std::string name() const override { return "failing"; }

   private:
    StampDataset inner_{10};
  };
  const FailingDataset dataset;
  FramePacer pacer(1.0);
  PrefetchOptions live;
  live.pacer = &pacer;
  live.drop_late = true;
  FramePrefetcher prefetcher(dataset, 0, 10, live);
  bool thrown = false;
  try {
    take_all(prefetcher, std::chrono::milliseconds(100));  // slow: earlier frames are dropped
  } catch (const InputError& e) {
    thrown = true;
    EXPECT_NE(std::string(e.what()).find("rgb/9.png"), std::string::npos) << e.what();
  }
  EXPECT_TRUE(thrown);
}

TEST(FramePrefetcher, DroppingFramesNeedsAPacedRun) {
  const StampDataset dataset(3);
  PrefetchOptions live;
  live.drop_late = true;
  try {
    FramePrefetcher prefetcher(dataset, 0, 3, live);
    ADD_FAILURE() << "no error";
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("--drop-late-frames"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace ddl::pipeline
