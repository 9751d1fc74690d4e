#pragma once
// Vocabulary training: hierarchical k-means++ over binary descriptors (Nister & Stewenius 2006),
// cluster centres by per-bit majority vote (the binary mean of Galvez-Lopez & Tardos 2012), then
// IDF word weights from the training images.

#include <atomic>
#include <cstddef>
#include <functional>
#include <opencv2/core.hpp>
#include <vector>

#include "ddl/vocabulary/vocabulary.h"
#include "ddl/vocabulary/vocabulary_config.h"

namespace ddl::vocabulary {

/// Progress of one tree level (root split = level 1).
struct TrainingProgress {
  int level = 0;               // 1..levels: the depth of the nodes being created
  std::size_t nodes_done = 0;  // parent nodes of this level split so far
  std::size_t nodes_total = 0;
};

struct TrainingHooks {
  /// Called after each split (serialised by a mutex, possibly from a worker thread).
  std::function<void(const TrainingProgress&)> on_progress;
  /// When it becomes true, training stops at the next split and throws ddl::Interrupted.
  const std::atomic<bool>* stop = nullptr;
};

struct TrainingStats {
  std::size_t images = 0;       // images with at least one descriptor (the N of the IDF)
  std::size_t descriptors = 0;  // descriptors clustered
  std::size_t nodes = 0;
  std::size_t words = 0;
  std::size_t splits = 0;                     // k-means runs
  std::size_t iterations = 0;                 // Lloyd iterations over all splits
  std::size_t splits_hit_max_iterations = 0;  // splits stopped by max_iterations, not convergence
  double seconds = 0.0;
};

/// Trains a vocabulary from the descriptors of each training image (one N x 32 CV_8U matrix per
/// image; empty matrices allowed). Deterministic: the same descriptors, config and seed give the
/// identical vocabulary for any thread count.
///
/// Algorithm. Level by level from the root, the descriptors of each node are split into at most
/// `branching` clusters by k-means: seeding by k-means++ (the first centre uniform, each next one
/// drawn with probability proportional to the squared Hamming distance to the nearest chosen
/// centre), then Lloyd iterations (assign to the nearest centre, ties to the lower index; centre =
/// per-bit majority vote, ties to 1) until no assignment changes or max_iterations. A node with at
/// most `branching` distinct descriptors gets one child per distinct descriptor; a node whose
/// descriptors are all equal, or at depth `levels`, is a word. Node ids are breadth-first.
/// Word weights: IDF = log(N / n_w), N the images with descriptors and n_w those with at least one
/// descriptor whose descent reaches word w (log N for a word no training descriptor reaches);
/// 1 for the tf and binary weightings.
///
/// Throws ddl::ConfigError for an invalid config, ddl::InputError when there are no descriptors,
/// ddl::Interrupted when stopped through hooks.stop.
Vocabulary train_vocabulary(const std::vector<cv::Mat>& image_descriptors,
                            const VocabularyConfig& config, const TrainingHooks& hooks = {},
                            TrainingStats* stats = nullptr);

}  // namespace ddl::vocabulary
