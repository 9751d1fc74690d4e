// `ddl_slam vocab`: train a binary bag-of-words vocabulary from ORB descriptors of images, and
// inspect a vocabulary file.

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <atomic>
#include <cctype>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <mutex>
#include <opencv2/imgcodecs.hpp>
#include <optional>
#include <set>
#include <string>
#include <thread>
#include <vector>

#include "cli_support.h"
#include "commands.h"
#include "ddl/core/error.h"
#include "ddl/core/timing.h"
#include "ddl/features/orb_extractor.h"
#include "ddl/vocabulary/bow_database.h"
#include "ddl/vocabulary/vocabulary.h"
#include "ddl/vocabulary/vocabulary_training.h"

namespace ddl::app {
namespace {

namespace fs = std::filesystem;

struct TrainArgs {
  std::vector<std::string> images;
  std::vector<std::string> exclude;
  std::size_t max_images = 0;
  int features = 1000;
  std::string out;
  vocabulary::VocabularyConfig config;
  std::string weighting = "tf-idf";
};

struct InfoArgs {
  std::string path;
  int repeat = 5;
};

struct EvalArgs {
  std::string vocabulary_path;
  std::vector<std::string> images;
  std::size_t max_images = 0;
  int features = 1000;
  int keyframe_every = 10;
  int threads = 1;
};

bool is_image_file(const fs::path& p) {
  std::string ext = p.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  static const std::set<std::string> kExtensions = {".jpg", ".jpeg", ".png", ".bmp",
                                                    ".ppm", ".pgm",  ".tif", ".tiff"};
  return kExtensions.contains(ext);
}

// Image paths from a list file: one per line, relative paths resolved against the list's folder,
// blank lines and '#' comments skipped.
std::vector<std::string> read_image_list(const fs::path& list) {
  std::ifstream in(list);
  if (!in) throw InputError::at(list.string(), "cannot open the image list");
  std::vector<std::string> out;
  std::string line;
  std::size_t line_no = 0;
  while (std::getline(in, line)) {
    ++line_no;
    const auto first = line.find_first_not_of(" \t\r");
    if (first == std::string::npos || line[first] == '#') continue;
    const auto last = line.find_last_not_of(" \t\r");
    fs::path p = line.substr(first, last - first + 1);
    if (p.is_relative()) p = list.parent_path() / p;
    if (!is_image_file(p)) {
      throw InputError::at_line(list.string(), line_no,
                                fmt::format("'{}' is not an image file name", p.string()));
    }
    out.push_back(p.string());
  }
  return out;
}

// Each argument is a directory (its image files, sorted by name, not recursive), an image file, or
// a text file listing images.
std::vector<std::string> collect_images(const std::vector<std::string>& args_images,
                                        const std::vector<std::string>& exclude,
                                        std::size_t max_images) {
  std::vector<std::string> all;
  for (const std::string& arg : args_images) {
    const fs::path p(arg);
    if (fs::is_directory(p)) {
      std::vector<std::string> in_dir;
      for (const auto& entry : fs::directory_iterator(p)) {
        if (entry.is_regular_file() && is_image_file(entry.path())) {
          in_dir.push_back(entry.path().string());
        }
      }
      std::sort(in_dir.begin(), in_dir.end());
      if (in_dir.empty()) throw InputError::at(arg, "directory holds no image files");
      all.insert(all.end(), in_dir.begin(), in_dir.end());
    } else if (!fs::exists(p)) {
      throw InputError::at(arg, "no such file or directory");
    } else if (is_image_file(p)) {
      all.push_back(arg);
    } else {
      const std::vector<std::string> listed = read_image_list(p);
      all.insert(all.end(), listed.begin(), listed.end());
    }
  }
  const std::set<std::string> excluded(exclude.begin(), exclude.end());
  std::erase_if(all, [&](const std::string& path) {
    return excluded.contains(fs::path(path).filename().string());
  });
  if (all.empty()) throw InputError("vocab: no images left");
  if (max_images > 0 && all.size() > max_images) {
    // An evenly spaced subset keeps the variety of a long sorted list (e.g. a video's frames).
    std::vector<std::string> subset;
    for (std::size_t i = 0; i < max_images; ++i) {
      subset.push_back(all[i * all.size() / max_images]);
    }
    all = std::move(subset);
  }
  return all;
}

// ORB descriptors of every image, with one extractor per thread (deterministic: each image's
// descriptors go to its own slot).
std::vector<cv::Mat> extract_descriptors(const std::vector<std::string>& images,
                                         const features::OrbExtractorConfig& orb_config,
                                         int threads, const std::atomic<bool>& stop) {
  std::vector<cv::Mat> descriptors(images.size());
  std::atomic<std::size_t> next{0};
  std::atomic<std::size_t> done{0};
  std::mutex mutex;
  std::exception_ptr error;
  Progress progress("extracting ORB", images.size());
  const auto work = [&] {
    features::OrbExtractor extractor(orb_config);
    while (true) {
      const std::size_t i = next.fetch_add(1);
      if (i >= images.size() || stop.load()) return;
      try {
        const cv::Mat gray = cv::imread(images[i], cv::IMREAD_GRAYSCALE);
        if (gray.empty()) throw InputError::at(images[i], "cannot read the image");
        descriptors[i] = extractor.extract(gray).descriptors;
      } catch (...) {
        const std::lock_guard lock(mutex);
        if (!error) error = std::current_exception();
        next = images.size();
        return;
      }
      const std::size_t n = ++done;
      const std::lock_guard lock(mutex);
      if (n < images.size()) progress.update(n);  // finish() prints the last line
    }
  };
  std::vector<std::thread> pool;
  for (int t = 1; t < threads; ++t) pool.emplace_back(work);
  work();
  for (std::thread& t : pool) t.join();
  if (error) std::rethrow_exception(error);
  if (stop.load()) throw Interrupted();
  progress.finish();
  return descriptors;
}

// The vocabulary's descriptor tag: fingerprint of the extractor's BRIEF sampling pattern.
std::uint64_t orb_descriptor_tag(const features::OrbExtractorConfig& orb_config) {
  const features::OrbExtractor extractor(orb_config);
  return vocabulary::descriptor_fingerprint(extractor.pattern().data(),
                                            sizeof(features::BriefPattern));
}

int run_train(TrainArgs args) {
  const std::optional<vocabulary::Weighting> weighting =
      vocabulary::parse_weighting(args.weighting);
  if (!weighting) {
    throw ConfigError::for_key("weighting", fmt::format("unknown weighting '{}'", args.weighting));
  }
  args.config.weighting = *weighting;
  args.config.validate();
  features::OrbExtractorConfig orb_config;
  orb_config.num_features = args.features;
  orb_config.validate();
  const std::atomic<bool>& stop = install_stop_handler();

  const std::vector<std::string> images =
      collect_images(args.images, args.exclude, args.max_images);
  const std::uint64_t descriptor_tag = orb_descriptor_tag(orb_config);
  spdlog::info(
      "vocab train: {} images, ORB {} features, {} levels, scale {}, BRIEF pattern "
      "fingerprint {:016x}",
      images.size(), orb_config.num_features, orb_config.num_levels, orb_config.scale_factor,
      descriptor_tag);
  const Stopwatch extract_watch;
  const std::vector<cv::Mat> descriptors =
      extract_descriptors(images, orb_config, args.config.threads, stop);
  const double extract_s = extract_watch.elapsed_ms() / 1000.0;
  std::size_t total = 0;
  for (const cv::Mat& d : descriptors) total += static_cast<std::size_t>(d.rows);
  spdlog::info("extracted {} descriptors in {:.1f} s ({:.0f} per image)", total, extract_s,
               static_cast<double>(total) / static_cast<double>(images.size()));

  vocabulary::TrainingHooks hooks;
  hooks.stop = &stop;
  std::unique_ptr<Progress> progress;
  int progress_level = 0;
  hooks.on_progress = [&](const vocabulary::TrainingProgress& p) {
    if (p.level != progress_level) {
      if (progress) progress->finish();
      progress = std::make_unique<Progress>(
          fmt::format("k-means level {}/{}", p.level, args.config.levels), p.nodes_total);
      progress_level = p.level;
    }
    if (p.nodes_done < p.nodes_total) progress->update(p.nodes_done);
  };
  vocabulary::TrainingStats stats;
  vocabulary::Vocabulary voc =
      vocabulary::train_vocabulary(descriptors, args.config, hooks, &stats);
  if (progress) progress->finish();
  voc.set_descriptor_tag(descriptor_tag);
  voc.save(args.out);

  std::printf(
      "vocabulary        %s (%.2f MB)\n"
      "images            %zu (%zu with descriptors)\n"
      "descriptors       %zu\n"
      "k, L, weighting   %d, %d, %s\n"
      "nodes, words      %zu, %zu\n"
      "k-means           %zu splits, %zu iterations, %zu stopped at --max-iterations\n"
      "time              extraction %.1f s, training %.1f s (%d thread%s)\n",
      args.out.c_str(), static_cast<double>(fs::file_size(args.out)) / 1e6, images.size(),
      stats.images, stats.descriptors, voc.branching(), voc.levels(),
      std::string(vocabulary::to_string(voc.weighting())).c_str(), voc.node_count(),
      voc.word_count(), stats.splits, stats.iterations, stats.splits_hit_max_iterations, extract_s,
      stats.seconds, args.config.threads, args.config.threads == 1 ? "" : "s");
  return kOk;
}

int run_info(const InfoArgs& args) {
  if (args.repeat < 1) throw ConfigError::for_key("repeat", "must be >= 1");
  std::vector<double> load_ms;
  vocabulary::Vocabulary voc;
  for (int i = 0; i < args.repeat; ++i) {
    const Stopwatch watch;
    voc = vocabulary::Vocabulary::load(args.path);
    load_ms.push_back(watch.elapsed_ms());
  }
  std::map<int, std::size_t> words_at_depth;
  for (vocabulary::NodeId n = 0; n < voc.node_count(); ++n) {
    if (voc.is_word(n)) ++words_at_depth[voc.depth(n)];
  }
  std::string depths;
  for (const auto& [depth, count] : words_at_depth) {
    depths += fmt::format("{}{}: {}", depths.empty() ? "" : ", ", depth, count);
  }
  const double weight_sum = [&] {
    double s = 0.0;
    for (vocabulary::WordId w = 0; w < voc.word_count(); ++w) s += voc.word_weight(w);
    return s;
  }();
  const std::uint64_t current_tag = orb_descriptor_tag(features::OrbExtractorConfig{});
  const std::string tag_note = voc.descriptor_tag() == 0 ? "not recorded"
                               : voc.descriptor_tag() == current_tag
                                   ? "matches this build's ORB descriptor"
                                   : "DIFFERS from this build's ORB descriptor: retrain";
  std::printf(
      "vocabulary        %s (%.2f MB)\n"
      "k, L, weighting   %d, %d, %s\n"
      "nodes             %zu\n"
      "words             %zu (by depth %s)\n"
      "mean word weight  %.3f\n"
      "descriptor tag    %016llx (%s)\n"
      "load time         %.1f ms (median of %d loads)\n",
      args.path.c_str(), static_cast<double>(fs::file_size(args.path)) / 1e6, voc.branching(),
      voc.levels(), std::string(vocabulary::to_string(voc.weighting())).c_str(), voc.node_count(),
      voc.word_count(), depths.c_str(), weight_sum / static_cast<double>(voc.word_count()),
      static_cast<unsigned long long>(voc.descriptor_tag()), tag_note.c_str(), median(load_ms),
      args.repeat);
  return kOk;
}

// Place recognition on an image sequence: every keyframe_every-th image goes into a BowDatabase;
// every other image queries it. A query is answered right when its best candidate is one of the
// two keyframes around it (the nearest views of the same place).
int run_eval(const EvalArgs& args) {
  if (args.keyframe_every < 2) throw ConfigError::for_key("keyframe-every", "must be >= 2");
  const vocabulary::Vocabulary voc = vocabulary::Vocabulary::load(args.vocabulary_path);
  features::OrbExtractorConfig orb_config;
  orb_config.num_features = args.features;
  orb_config.validate();
  if (voc.descriptor_tag() != 0 && voc.descriptor_tag() != orb_descriptor_tag(orb_config)) {
    spdlog::warn("{} was trained for another ORB descriptor pattern", args.vocabulary_path);
  }
  const std::atomic<bool>& stop = install_stop_handler();
  const std::vector<std::string> images = collect_images(args.images, {}, args.max_images);
  if (images.size() < 2) {
    // Image 0 is a keyframe and the images that are not keyframes query: one image queries none.
    throw InputError(fmt::format(
        "vocab eval --images: {} image(s); the evaluation needs at least 2", images.size()));
  }
  const std::vector<cv::Mat> descriptors =
      extract_descriptors(images, orb_config, args.threads, stop);

  std::vector<vocabulary::BowVector> bows(images.size());
  std::vector<double> transform_ms;
  for (std::size_t i = 0; i < images.size(); ++i) {
    const Stopwatch watch;
    vocabulary::BowVector bow;
    vocabulary::FeatureVector features;
    voc.transform(descriptors[i], 4, bow, features);
    transform_ms.push_back(watch.elapsed_ms());
    bows[i] = std::move(bow);
  }
  vocabulary::BowDatabase db;
  const auto every = static_cast<std::size_t>(args.keyframe_every);
  for (std::size_t i = 0; i < images.size(); i += every) db.add(i, bows[i]);
  std::size_t queries = 0;
  std::size_t right = 0;
  std::vector<double> right_scores;
  std::vector<double> wrong_scores;  // best candidate outside the bracketing keyframes
  std::vector<double> query_ms;
  for (std::size_t q = 0; q < images.size(); ++q) {
    if (q % every == 0) continue;
    const Stopwatch watch;
    const std::vector<vocabulary::QueryResult> results = db.query(bows[q], 0);
    query_ms.push_back(watch.elapsed_ms());
    ++queries;
    const auto near = [&](vocabulary::EntryId id) { return (id <= q ? q - id : id - q) < every; };
    if (!results.empty() && near(results[0].entry_id)) ++right;
    for (const vocabulary::QueryResult& r : results) {
      if (near(r.entry_id)) {
        right_scores.push_back(r.score);
        break;
      }
    }
    for (const vocabulary::QueryResult& r : results) {
      if (!near(r.entry_id)) {
        wrong_scores.push_back(r.score);
        break;
      }
    }
  }
  std::printf(
      "vocabulary        %s (k %d, L %d, %zu words)\n"
      "images            %zu: %zu keyframes (every %d), %zu queries\n"
      "top-1 right       %zu of %zu (%.1f%%): best candidate is a keyframe within %d images\n"
      "median score      %.4f nearest keyframe, %.4f best other keyframe\n"
      "median time       transform %.2f ms (with feature vector), query %.3f ms\n",
      args.vocabulary_path.c_str(), voc.branching(), voc.levels(), voc.word_count(), images.size(),
      db.size(), args.keyframe_every, queries, right, queries,
      queries > 0 ? 100.0 * static_cast<double>(right) / static_cast<double>(queries) : 0.0,
      args.keyframe_every - 1, median(right_scores), median(wrong_scores), median(transform_ms),
      median(query_ms));
  return kOk;
}

}  // namespace

void add_vocab_command(CLI::App& app, int& exit_code) {
  CLI::App* vocab = app.add_subcommand(
      "vocab",
      "Binary bag-of-words vocabulary for loop closing and relocalization: train one from ORB "
      "descriptors of images (hierarchical k-means++, TF-IDF), or inspect a vocabulary file. "
      "See docs/vocabulary.md.");
  vocab->require_subcommand(1);

  auto train = std::make_shared<TrainArgs>();
  CLI::App* cmd = vocab->add_subcommand(
      "train",
      "Extract ORB features (DDL-SLAM's own extractor, default TUM settings: scale 1.2, 8 levels, "
      "FAST 20/7) from every training image and build a k-ary vocabulary tree of L levels by "
      "hierarchical k-means++ with per-bit majority centres; word weights are IDF = log(N / n_w) "
      "over the training images. Deterministic for a seed, whatever --threads. Use images that "
      "are not your evaluation sequence.");
  cmd->add_option("--images", train->images,
                  "Training images: directories (their .jpg/.png/... files, sorted, not "
                  "recursive), image files, or text files listing one image per line (relative "
                  "to the list's folder; '#' comments)")
      ->required();
  cmd->add_option("--exclude", train->exclude,
                  "File names (without folder) to leave out, e.g. basketball1.png");
  cmd->add_option("--max-images", train->max_images,
                  "Use at most this many images, evenly spaced over the sorted list (0 = all)")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  cmd->add_option("--features", train->features, "ORB features per image")->capture_default_str();
  cmd->add_option("--out", train->out, "Vocabulary file to write (.dvoc)")->required();
  cmd->add_option("--k", train->config.branching, "Branching factor: children per node (2..64)")
      ->capture_default_str();
  cmd->add_option("--levels", train->config.levels, "Depth L of the tree (1..10)")
      ->capture_default_str();
  cmd->add_option("--seed", train->config.seed, "Seed of the k-means++ initialisation")
      ->capture_default_str();
  cmd->add_option("--max-iterations", train->config.max_iterations,
                  "Most k-means iterations per node (stops earlier when assignments settle)")
      ->capture_default_str();
  cmd->add_option("--weighting", train->weighting, "Word weighting: tf-idf, tf, idf or binary")
      ->check(CLI::IsMember({"tf-idf", "tf", "idf", "binary"}))
      ->capture_default_str();
  cmd->add_option("--threads", train->config.threads,
                  "Threads for ORB extraction and training (the result does not depend on it)")
      ->capture_default_str();
  cmd->callback(
      [train, &exit_code] { exit_code = run_guarded([&] { return run_train(*train); }); });

  auto eval = std::make_shared<EvalArgs>();
  CLI::App* eval_cmd = vocab->add_subcommand(
      "eval",
      "Place-recognition check of a vocabulary on an image sequence (e.g. a TUM sequence's rgb/ "
      "folder): every Nth image becomes a keyframe in a BoW database, every other image "
      "queries it; reports how often the best candidate is one of the two keyframes around the "
      "query, median scores and the transform/query times.");
  eval_cmd->add_option("vocabulary", eval->vocabulary_path, "Vocabulary file (.dvoc)")->required();
  eval_cmd
      ->add_option("--images", eval->images,
                   "The sequence in order: a directory (sorted by file name), image files or "
                   "list files, as for train")
      ->required();
  eval_cmd
      ->add_option("--max-images", eval->max_images,
                   "Use at most this many images, evenly spaced (0 = all)")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  eval_cmd->add_option("--features", eval->features, "ORB features per image")
      ->capture_default_str();
  eval_cmd
      ->add_option("--keyframe-every", eval->keyframe_every, "Every Nth image is a keyframe (>= 2)")
      ->capture_default_str();
  eval_cmd->add_option("--threads", eval->threads, "Threads for ORB extraction")
      ->capture_default_str();
  eval_cmd->callback(
      [eval, &exit_code] { exit_code = run_guarded([&] { return run_eval(*eval); }); });

  auto info = std::make_shared<InfoArgs>();
  CLI::App* info_cmd = vocab->add_subcommand(
      "info",
      "Print a vocabulary file's branching k, depth L, weighting, node and word counts "
      "and its load time.");
  info_cmd->add_option("file", info->path, "Vocabulary file (.dvoc)")->required();
  info_cmd->add_option("--repeat", info->repeat, "Load this many times; report the median time")
      ->capture_default_str();
  info_cmd->callback(
      [info, &exit_code] { exit_code = run_guarded([&] { return run_info(*info); }); });
}

}  // namespace ddl::app
