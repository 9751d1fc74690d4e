#pragma once
// The body of `ddl_slam run`, shared with `ddl_slam bench` so that both run a sequence through
// exactly the same code path (settings, dataset, vocabulary, outputs, evaluation, mask metrics).

#include <atomic>
#include <cstddef>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>

#include "ddl/pipeline/system_config.h"
#include "ddl/vocabulary/vocabulary.h"

namespace ddl::app {

struct RunArgs {
  std::string sequence;
  std::string camera;
  std::string config_path;
  std::string output_dir = "out/run";
  std::string vocabulary_path;
  std::string dataset_kind = "auto";
  std::string associations = "auto";
  std::string mode;
  std::string shared_dir;
  std::size_t max_frames = 0;
  std::size_t first_frame = 0;
  double playback_rate = 0.0;  // 0: as fast as possible; 1: real time
  bool drop_late_frames = false;
  bool no_eval = false;
  bool no_dynamic = false;
  bool no_loop = false;
  bool no_octomap = false;
  bool no_inpainting = false;
  bool save_masks = false;
  bool save_inpainted = false;
  std::string load_map;            // --load-map FILE: start in a saved sparse map
  std::string save_map;            // --save-map FILE: write the sparse map at the end
  bool localization_only = false;  // --localization-only: track against the loaded map only
  std::string segmentation;
  bool viewer = false;            // --viewer: the viewer window
  std::string save_viewer_dir;    // --save-viewer DIR: the viewer's images
  std::string save_viewer_video;  // --save-viewer-video FILE: the viewer's views as a video
  int viewer_every = 1;           // --viewer-every N
};

struct RunResult {
  bool interrupted = false;
  nlohmann::json summary;  // what <out>/summary.json holds
};

/// The vocabulary file to use: the flag, else $DDL_VOCABULARY, else the one shipped in vocab/.
std::string resolve_vocabulary(const std::string& flag);

/// Loads a vocabulary, logging its size and load time.
std::shared_ptr<const vocabulary::Vocabulary> load_vocabulary(const std::string& path);

/// The settings of a run: the --config file (or the defaults) with the flags applied, validated.
/// Throws ddl::InputError / ddl::ConfigError naming the file or key.
pipeline::SystemConfig make_system_config(const RunArgs& args);

/// Runs one sequence with its outputs in args.output_dir, progress on stderr. `vocabulary`:
/// already loaded, or nullptr to load resolve_vocabulary(args.vocabulary_path). `stop` ends the
/// run cleanly after the current frame. Throws ddl::InputError / ddl::ConfigError for bad input.
RunResult run_sequence_command(const RunArgs& args,
                               std::shared_ptr<const vocabulary::Vocabulary> vocabulary,
                               const std::atomic<bool>* stop);

}  // namespace ddl::app
