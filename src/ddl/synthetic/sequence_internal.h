#pragma once
// Helpers shared by the sequence sources and the writer (not part of the public API).

#include <cmath>
#include <cstdint>
#include <memory>

#include "ddl/synthetic/sequence.h"

namespace ddl::synthetic {

/// Microseconds from the first frame to frame i at `fps` (rounded, so stamps print exactly).
inline std::int64_t stamp_offset_us(std::size_t i, double fps) {
  return std::llround(static_cast<double>(i) * 1e6 / fps);
}

/// Accelerometer readings are written this far (seconds) beyond the first and last frame: more
/// than the window io::AccelerometerLog averages over around a frame's stamp.
inline constexpr double kAccelerometerMarginS = 0.05;
static_assert(kAccelerometerMarginS > io::AccelerometerLog::kDefaultHalfWindowS);

/// RGB stamp of frame i: exactly the value its 6-decimal text parses back to.
double rgb_stamp(const SequenceConfig& config, std::size_t i);
/// Depth stamp: RGB stamp plus a seeded jitter in [-jitter, jitter], whole microseconds.
double depth_stamp(const SequenceConfig& config, std::size_t i, double rgb_stamp_s);

std::unique_ptr<SequenceSource> make_room_sequence(const SequenceConfig& config);
std::unique_ptr<SequenceSource> make_composite_sequence(const SequenceConfig& config);

}  // namespace ddl::synthetic
