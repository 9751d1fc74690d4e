#include "ddl/tracking/keyframe_decision.h"

namespace ddl::tracking {

CloseCounts count_close_points(const Frame& frame) {
  CloseCounts counts;
  for (std::size_t i = 0; i < frame.size(); ++i) {
    if (!frame.is_close(i)) continue;
    const map::MapPointPtr& point = frame.map_point(i);
    if (point && !frame.is_outlier(i)) {
      ++counts.tracked;
      if (point->num_keyframes() >= 2) ++counts.tracked_established;
    } else {
      ++counts.non_tracked;
    }
  }
  return counts;
}

int min_observations_for(std::size_t keyframes_in_map) { return keyframes_in_map <= 2 ? 2 : 3; }

bool need_new_keyframe(const KeyFrameConfig& config, const KeyFrameContext& c) {
  if (c.mapping.stopped) return false;
  const auto max_frames = static_cast<FrameId>(config.max_frames);
  const auto min_frames = static_cast<FrameId>(config.min_frames);
  // Shortly after a relocalization the map is not extended (unless it is still tiny).
  const auto after_relocalization = static_cast<FrameId>(config.frames_after_relocalization);
  if (c.frame_id < c.last_relocalization_frame_id + after_relocalization &&
      c.keyframes_in_map > static_cast<std::size_t>(config.max_frames)) {
    return false;
  }
  const bool mapping_idle = c.mapping.accepts_keyframes;
  const int tracked_close =
      config.close_needs_two_keyframes ? c.close.tracked_established : c.close.tracked;
  const bool need_close = tracked_close < config.tracked_close_max &&
                          c.close.non_tracked > config.non_tracked_close_min;
  const float ratio =
      c.keyframes_in_map < 2 ? config.reference_ratio_single_keyframe : config.reference_ratio;
  const float inliers = static_cast<float>(c.inliers);
  const float reference = static_cast<float>(c.reference_tracked_points);

  const bool c1a = c.frame_id >= c.last_keyframe_frame_id + max_frames;
  const bool c1b = c.frame_id >= c.last_keyframe_frame_id + min_frames && mapping_idle;
  const bool c1c = inliers < reference * config.weak_tracking_ratio || need_close;
  const bool c2 = (inliers < reference * ratio || need_close) && c.inliers > config.min_inliers;
  if (!((c1a || c1b || c1c) && c2)) return false;
  if (mapping_idle) return true;
  // Mapping is busy: the pipeline interrupts its local BA when the keyframe arrives; queue it
  // unless the queue is already long.
  return c.mapping.queued_keyframes < static_cast<std::size_t>(config.max_queued_keyframes);
}

}  // namespace ddl::tracking
