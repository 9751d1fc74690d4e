#pragma once
#include <cstdint>

namespace ddl::map {

/// Keyframe and map point ids: unique within one Map, increasing in creation order. Containers
/// keyed and sorted by id make every iteration order deterministic (never key by pointer).
using KeyFrameId = std::uint64_t;
using MapPointId = std::uint64_t;

}  // namespace ddl::map
