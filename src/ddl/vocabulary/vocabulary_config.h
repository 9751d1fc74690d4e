#pragma once
// Parameters of vocabulary training (hierarchical k-means++ over binary descriptors, Nister &
// Stewenius 2006; Galvez-Lopez & Tardos 2012 for binary descriptors).

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

namespace ddl::vocabulary {

/// How a word's weight in a BoW vector is formed (DBoW2's weighting schemes). Every scheme ends
/// with the vector L1-normalised, so term frequency is implicit in the accumulated weight.
enum class Weighting : std::uint32_t {
  kTfIdf = 0,   // each occurrence adds the word's IDF, log(N_images / n_images_with_word)
  kTf = 1,      // each occurrence adds 1
  kIdf = 2,     // a present word gets its IDF once
  kBinary = 3,  // a present word gets 1 once
};

/// "tf-idf", "tf", "idf" or "binary".
std::string_view to_string(Weighting weighting);
/// Inverse of to_string; nullopt for an unknown name.
std::optional<Weighting> parse_weighting(std::string_view name);

struct VocabularyConfig {
  int branching = 10;       // k: children per node (k-means clusters per split), 2..64
  int levels = 6;           // L: depth of the tree below the root (words at depth <= L), 1..10
  int max_iterations = 30;  // k-means iterations per node at most (stops early when stable)
  std::uint64_t seed = 1;   // seeds k-means++ initialisation; same seed + data = same tree
  Weighting weighting = Weighting::kTfIdf;  // word weighting of BoW vectors
  int threads = 1;  // worker threads for training; the tree is identical for any count

  /// Throws ddl::ConfigError naming the field when a value is out of range.
  void validate() const;
};

}  // namespace ddl::vocabulary
