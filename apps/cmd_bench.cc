// `ddl_slam bench`: the paper's Tables 1-3 (ATE, RPE translational, RPE rotational) and mask
// quality over a list of sequences, each run with dynamic removal and without (`--no-dynamic`,
// the paper's ORB-SLAM2 column) through the same code path as `ddl_slam run`.

#include <fmt/format.h>
#include <spdlog/spdlog.h>
#include <yaml-cpp/yaml.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <memory>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "cli_support.h"
#include "commands.h"
#include "ddl/config/camera_config.h"
#include "ddl/config/dataset_config.h"
#include "ddl/config/system_config.h"
#include "ddl/core/error.h"
#include "ddl/core/filesystem.h"
#include "ddl/eval/benchmark_tables.h"
#include "ddl/io/dataset_factory.h"
#include "run_command.h"

namespace ddl::app {
namespace {
namespace fs = std::filesystem;
using nlohmann::json;

struct BenchArgs {
  std::vector<std::string> sequences;
  std::string suite;
  std::string output_dir = "out/bench";
  bool reuse_baseline = false;       // take finished --no-dynamic runs from output_dir
  std::string baseline_config_path;  // settings of the --no-dynamic runs (empty: run.config_path)
  RunArgs run;  // settings shared by every run (sequence, output_dir and no_dynamic set per run)

  /// The arguments of the --no-dynamic column's runs (before sequence and output folder).
  RunArgs baseline_run() const {
    RunArgs baseline = run;
    if (!baseline_config_path.empty()) baseline.config_path = baseline_config_path;
    return baseline;
  }
};

struct Sequence {
  std::string name;
  std::string dir;
  bool from_suite = false;  // found in --suite (skipped when malformed) or named (an error)
};

/// The sequences to run, validated before anything runs. Named folders must exist and hold
/// rgb.txt and groundtruth.txt (an error otherwise); suite subfolders with rgb.txt but without
/// groundtruth.txt are skipped with a warning, recorded in `skipped`.
std::vector<Sequence> collect_sequences(const BenchArgs& args, json& skipped) {
  std::vector<Sequence> out;
  auto check = [](const fs::path& dir) {
    io::require_sequence_folder(dir.string());
    if (!fs::exists(dir / "rgb.txt")) {
      throw InputError::at(dir.string(), "not a TUM-layout sequence (no rgb.txt)");
    }
    if (!fs::exists(dir / "groundtruth.txt")) {
      throw InputError::at(dir.string(),
                           "no groundtruth.txt: bench needs ground truth for its tables");
    }
  };
  for (const std::string& s : args.sequences) {
    const fs::path dir = fs::path(s).lexically_normal();
    check(dir);
    // The folder's own name, also for "." or "seq/": the row's label and its output folder.
    const fs::path full = fs::absolute(dir).lexically_normal();
    const fs::path name = full.has_filename() ? full.filename() : full.parent_path().filename();
    out.push_back({name.string(), dir.string()});
  }
  if (!args.suite.empty()) {
    const fs::path suite(args.suite);
    if (!fs::is_directory(suite)) throw InputError::at(args.suite, "suite folder not found");
    std::vector<fs::path> dirs;
    for (const auto& entry : fs::directory_iterator(suite)) {
      if (entry.is_directory() && fs::exists(entry.path() / "rgb.txt")) dirs.push_back(entry);
    }
    std::sort(dirs.begin(), dirs.end());
    for (const fs::path& dir : dirs) {
      if (!fs::exists(dir / "groundtruth.txt")) {
        spdlog::warn("bench: {} has no groundtruth.txt, skipped", dir.string());
        skipped.push_back({{"sequence", dir.filename().string()},
                           {"reason", "no groundtruth.txt in " + dir.string()}});
        continue;
      }
      out.push_back({dir.filename().string(), dir.string(), true});
    }
    if (dirs.empty()) {
      throw InputError::at(args.suite,
                           "no sequence folders (subfolders with rgb.txt) in the suite");
    }
  }
  if (out.empty()) throw InputError("bench: no sequence to run (give --sequences or --suite)");
  std::set<std::string> names;
  for (const Sequence& s : out) {
    if (!names.insert(s.name).second) {
      throw InputError::at(s.dir, "two sequences are named " + s.name +
                                      "; their outputs would collide in the output folder");
    }
  }
  return out;
}

json settings_json(const BenchArgs& args, std::size_t sequences) {
  const RunArgs& r = args.run;
  return {{"mode", r.mode},
          {"max_frames", r.max_frames},
          {"first_frame", r.first_frame},
          {"config", r.config_path.empty() ? "defaults" : r.config_path},
          {"baseline_config",
           args.baseline_config_path.empty() ? "as config" : args.baseline_config_path},
          {"camera", r.camera.empty() ? "per folder" : r.camera},
          {"segmentation", r.segmentation.empty() ? "from the settings" : r.segmentation},
          {"sequences", sequences},
          {"reuse_baseline", args.reuse_baseline}};
}

std::string file_text(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

/// What of an effective configuration decides a --no-dynamic run's trajectory: all but the
/// dynamic-removal and dense-stage sections and the mask pictures switch.
std::string trajectory_settings(const std::string& config_yaml) {
  YAML::Node node = YAML::Load(config_yaml);
  for (const char* key : {"dynamic", "dense", "save_masks"}) node.remove(key);
  YAML::Emitter out;
  out << node;
  return out.c_str();
}

/// Why the finished --no-dynamic run in `dir` (its `summary`) cannot stand in for `run`, or
/// std::nullopt when it can: it must have had the same part of the sequence, the same camera and
/// the same settings but for those that do not change its trajectory.
std::optional<std::string> reuse_mismatch(const json& summary, const fs::path& dir,
                                          const RunArgs& run) {
  if (summary.value("first_frame", json()) != json(run.first_frame) ||
      summary.value("max_frames", json()) != json(run.max_frames)) {
    return fmt::format(
        "it ran with first frame {} and max frames {}, this bench asks for {} and {}",
        summary.value("first_frame", json()).dump(), summary.value("max_frames", json()).dump(),
        run.first_frame, run.max_frames);
  }
  const camera::PinholeCamera camera = config::resolve_dataset_camera(
      run.sequence, run.camera, io::parse_dataset_kind(run.dataset_kind, "--dataset-kind"));
  if (file_text(dir / "camera.yaml") != config::camera_to_yaml(camera)) {
    return std::string("its camera.yaml is not this bench's camera of the sequence");
  }
  try {
    if (trajectory_settings(file_text(dir / "config.yaml")) !=
        trajectory_settings(config::system_config_to_yaml(make_system_config(run)))) {
      return std::string(
          "its config.yaml differs from the baseline's settings (beyond dynamic, dense and "
          "save_masks)");
    }
  } catch (const YAML::Exception& e) {
    return fmt::format("its config.yaml cannot be read: {}", e.what());
  }
  return std::nullopt;
}

/// The summary.json of a finished run in `dir` (not interrupted, not failed), if there is one.
std::optional<json> finished_summary(const fs::path& dir) {
  std::ifstream in(dir / "summary.json");
  if (!in) return std::nullopt;
  json summary = json::parse(in, nullptr, /*allow_exceptions=*/false);
  if (summary.is_discarded() || !summary.is_object() || summary.value("interrupted", true) ||
      summary.value("failed", true)) {
    return std::nullopt;
  }
  return summary;
}

int bench(const BenchArgs& args) {
  const auto& stop = install_stop_handler();
  json skipped = json::array();
  std::vector<Sequence> sequences = collect_sequences(args, skipped);
  const fs::path out_dir(args.output_dir);
  create_folder(out_dir, "the benchmark's outputs");

  // The settings are the same for every sequence: a bad --config, --baseline-config, --mode or
  // --segmentation is reported once, as bad input (exit 2), before any run.
  make_system_config(args.run);
  if (!args.baseline_config_path.empty()) make_system_config(args.baseline_run());
  // Every sequence is opened once too, as its runs will open it: its camera (from --camera, its
  // folder name or its camera.yaml), its lists, the images they name and its ground truth. A
  // malformed one stops the bench before its first run (exit code 2), not halfway through.
  io::DatasetOptions dataset_options;
  dataset_options.kind = io::parse_dataset_kind(args.run.dataset_kind, "--dataset-kind");
  dataset_options.sequence.association =
      io::parse_association_source(args.run.associations, "--associations");
  std::vector<Sequence> valid;
  for (const Sequence& s : sequences) {
    try {
      dataset_options.camera =
          config::resolve_dataset_camera(s.dir, args.run.camera, dataset_options.kind);
      io::open_dataset(s.dir, dataset_options);
      valid.push_back(s);
    } catch (const Error& e) {
      if (!s.from_suite) throw;
      spdlog::warn("bench: {} skipped: {}", s.dir, e.what());
      skipped.push_back({{"sequence", s.name}, {"reason", e.what()}});
    }
  }
  sequences = std::move(valid);
  if (sequences.empty()) throw InputError("bench: no sequence of the suite can be opened");
  const auto vocabulary = load_vocabulary(resolve_vocabulary(args.run.vocabulary_path));
  const json settings = settings_json(args, sequences.size());
  std::vector<eval::BenchmarkRow> rows;
  auto write_tables = [&] {
    const json tables = eval::benchmark_tables(rows, settings, skipped);
    write_file_atomically(out_dir / "tables.json", "the bench's tables",
                          tables.dump(2, ' ', false, json::error_handler_t::replace) + "\n");
    write_file_atomically(out_dir / "tables.md", "the bench's tables",
                          eval::benchmark_tables_markdown(tables));
  };

  bool interrupted = false;
  bool failed = false;
  for (std::size_t i = 0; i < sequences.size() && !interrupted; ++i) {
    const Sequence& seq = sequences[i];
    eval::BenchmarkRow row;
    row.sequence = seq.name;
    for (const bool dynamic : {true, false}) {
      const char* column = dynamic ? "dynamic" : "no_dynamic";
      std::fprintf(stderr, "bench [%zu/%zu] %s, %s\n", i + 1, sequences.size(), seq.name.c_str(),
                   dynamic ? "with dynamic removal" : "without dynamic removal (--no-dynamic)");
      RunArgs run = dynamic ? args.run : args.baseline_run();
      run.sequence = seq.dir;
      run.output_dir = (out_dir / seq.name / column).string();
      run.no_dynamic = !dynamic;
      if (!dynamic && args.reuse_baseline) {
        if (std::optional<json> summary = finished_summary(run.output_dir)) {
          if (const std::optional<std::string> why =
                  reuse_mismatch(*summary, run.output_dir, run)) {
            std::fprintf(stderr, "bench [%zu/%zu] %s: not reusing %s: %s\n", i + 1,
                         sequences.size(), seq.name.c_str(), run.output_dir.c_str(), why->c_str());
          } else {
            std::fprintf(stderr, "bench [%zu/%zu] %s: reusing %s/summary.json\n", i + 1,
                         sequences.size(), seq.name.c_str(), run.output_dir.c_str());
            row.baseline = std::move(*summary);
            continue;
          }
        }
      }
      try {
        const RunResult result = run_sequence_command(run, vocabulary, &stop);
        (dynamic ? row.ours : row.baseline) = result.summary;
        if (result.interrupted) {
          interrupted = true;
          break;
        }
      } catch (const Error& e) {
        spdlog::error("bench: {} ({}) failed: {}", seq.name, column, e.what());
        skipped.push_back({{"sequence", seq.name},
                           {"reason", fmt::format("{} run failed: {}", column, e.what())}});
        failed = true;
        break;
      }
    }
    if (interrupted) {
      skipped.push_back({{"sequence", seq.name}, {"reason", "interrupted (Ctrl-C)"}});
    } else if (row.ours.is_object() && row.baseline.is_object()) {
      rows.push_back(std::move(row));
    }
    write_tables();  // after every sequence, so finished results are never lost
  }
  std::fputs(
      eval::benchmark_tables_markdown(eval::benchmark_tables(rows, settings, skipped)).c_str(),
      stdout);
  std::printf("\ntables in %s and %s\n", (out_dir / "tables.md").string().c_str(),
              (out_dir / "tables.json").string().c_str());
  if (interrupted) return kInterrupted;
  return failed ? kFailure : kOk;
}

}  // namespace

void add_bench_command(CLI::App& app, int& exit_code) {
  auto args = std::make_shared<BenchArgs>();
  args->run.mode = "deterministic";
  CLI::App* cmd = app.add_subcommand(
      "bench",
      "The paper's Tables 1-3 over several sequences: each is run twice through the same code "
      "path as `ddl_slam run`, with dynamic removal (DDL-SLAM) and with --no-dynamic (the paper's "
      "ORB-SLAM2 column), sequentially. Writes <out>/<seq>/{dynamic,no_dynamic}/ (normal run "
      "outputs) and <out>/tables.md + tables.json: ATE, RPE translational (m/s) and rotational "
      "(deg/s) with RMSE, mean, median and S.D. of both columns and the improvement "
      "(ORB-SLAM2 - DDL-SLAM) / ORB-SLAM2 x 100, mask IoU/precision/recall against "
      "dynamic_mask/ when the sequence has it, and frames tracked. Every named sequence needs "
      "groundtruth.txt (error otherwise); suite folders without it are skipped with a warning. "
      "Ctrl-C stops after the current frame; the tables then hold the finished sequences.");
  cmd->add_option("--sequences", args->sequences, "Sequence folders (TUM layout)");
  cmd->add_option("--suite", args->suite,
                  "A folder of sequences: every subfolder with rgb.txt, in name order");
  cmd->add_option("--out", args->output_dir, "Output folder")->capture_default_str();
  cmd->add_option("--mode", args->run.mode,
                  "deterministic (reproducible) or threaded; overrides the settings file")
      ->check(CLI::IsMember({"deterministic", "threaded"}))
      ->capture_default_str();
  cmd->add_option("--config", args->run.config_path,
                  "System settings (YAML) for every run, as `ddl_slam run --config`");
  cmd->add_option("--baseline-config", args->baseline_config_path,
                  "System settings (YAML) for the --no-dynamic column's runs instead of --config, "
                  "e.g. `tracking: {motion_prior: {enabled: false}}` for ORB-SLAM2's motion-only "
                  "BA (docs/evaluation.md)");
  cmd->add_option("--camera", args->run.camera,
                  "Camera for every sequence (tum1, tum2, tum3, bonn, synthetic or a YAML file); "
                  "default: per folder, as `ddl_slam run`");
  cmd->add_option("--max-frames", args->run.max_frames,
                  "Process at most this many frames of each sequence (0 = all)")
      ->check(CLI::NonNegativeNumber);
  cmd->add_option("--first-frame", args->run.first_frame, "Skip the frames before this index")
      ->check(CLI::NonNegativeNumber);
  cmd->add_option("--vocabulary", args->run.vocabulary_path,
                  "ORB vocabulary file; default $DDL_VOCABULARY or the one shipped in vocab/");
  cmd->add_option("--segmentation", args->run.segmentation,
                  "Segmentation backend: onnx (default model in the shared folder), folder, none");
  cmd->add_option("--shared-dir", args->run.shared_dir,
                  "Shared data folder (models); default $DDL_SHARED_DIR or ../shared");
  cmd->add_flag("--no-loop", args->run.no_loop, "Disable loop closing in every run");
  cmd->add_flag("--reuse-baseline", args->reuse_baseline,
                "Take the --no-dynamic runs already finished in the output folder "
                "(<out>/<seq>/no_dynamic/summary.json) instead of running them again; they do not "
                "depend on the dynamic-removal settings, but the other options must match");
  cmd->add_flag("--no-octomap", args->run.no_octomap, "Do not build octree maps (faster)");
  cmd->add_flag("--no-inpainting", args->run.no_inpainting, "Do not repair keyframes (faster)");
  cmd->callback([args, &exit_code] {
    if (args->sequences.empty() && args->suite.empty()) {
      throw CLI::ValidationError("bench", "give --sequences and/or --suite");
    }
    exit_code = run_guarded([&] { return bench(*args); });
  });
}

}  // namespace ddl::app
