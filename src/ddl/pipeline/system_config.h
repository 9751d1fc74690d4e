#pragma once
// Configuration of the whole SLAM system: one struct per stage (each with its own defaults and
// validate()). Read from YAML only by ddl::config (config/system_config.h); written back as the
// effective configuration next to every run's outputs.

#include <cstddef>

#include "ddl/features/orb_extractor.h"
#include "ddl/loop/loop_closer.h"
#include "ddl/mapping/local_mapper.h"
#include "ddl/tracking/tracker.h"

namespace ddl::pipeline {

enum class RunMode {
  kDeterministic,  // all stages inline, reproducible (tests, evaluation)
  kThreaded,       // mapping and loop closing in their own threads (live, throughput)
};

struct SystemConfig {
  RunMode mode = RunMode::kDeterministic;   // see System
  std::size_t keyframe_queue_capacity = 4;  // bounded queues between stages (threaded mode)
  tracking::TrackerConfig tracking;         // ORB extraction settings live in tracking.orb
  mapping::LocalMapperConfig mapping;
  loop::LoopCloserConfig loop;

  /// Throws ddl::ConfigError naming the key.
  void validate() const;
};

}  // namespace ddl::pipeline
