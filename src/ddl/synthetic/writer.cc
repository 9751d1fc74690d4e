// Writing a sequence in the TUM RGB-D layout, plus the extra ground truth.

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <future>

#include "ddl/core/error.h"
#include "ddl/core/filesystem.h"
#include "ddl/io/trajectory_io.h"
#include "ddl/synthetic/png_writer.h"
#include "ddl/synthetic/random.h"
#include "ddl/synthetic/sequence_internal.h"

namespace ddl::synthetic {
namespace fs = std::filesystem;
namespace {

void write_png(const std::string& path, const cv::Mat& image, int compression) {
  write_png_file(path, image, compression);
}

void write_text(const std::string& path, const std::string& text) {
  std::ofstream file(path, std::ios::binary | std::ios::trunc);
  file << text;
  file.flush();
  if (!file) {
    throw OutputError::at(path, fmt::format("cannot write the file: {}", std::strerror(errno)));
  }
}

std::string yaml_double(double v) { return fmt::format("{}", v); }

std::string camera_yaml(const camera::PinholeCamera& c) {
  return fmt::format(
      "# Camera of this sequence (ddl_slam synth). Flat keys under `camera:`; distortion is\n"
      "# k1 k2 p1 p2 k3 (OpenCV order); depth_factor = raw depth units per metre.\n"
      "camera:\n"
      "  name: {}\n"
      "  width: {}\n"
      "  height: {}\n"
      "  fx: {}\n"
      "  fy: {}\n"
      "  cx: {}\n"
      "  cy: {}\n"
      "  distortion: [{}, {}, {}, {}, {}]\n"
      "  depth_factor: {}\n"
      "  fps: {}\n{}",
      c.name, c.width, c.height, yaml_double(c.fx), yaml_double(c.fy), yaml_double(c.cx),
      yaml_double(c.cy), yaml_double(c.distortion[0]), yaml_double(c.distortion[1]),
      yaml_double(c.distortion[2]), yaml_double(c.distortion[3]), yaml_double(c.distortion[4]),
      yaml_double(c.depth_factor), yaml_double(c.fps),
      c.depth_time_offset_s
          ? fmt::format("  depth_time_offset_s: {}  # depth captured at its stamp plus this\n",
                        yaml_double(*c.depth_time_offset_s))
          : std::string());
}

/// accelerometer.txt in the TUM format, the readings up to `last_stamp_s` plus a margin wider than
/// the window io::AccelerometerLog averages over; nothing (and no stale file) when the source has
/// none.
void write_accelerometer(const SequenceSource& source, const std::string& path,
                         double last_stamp_s) {
  std::string text;
  for (const io::AccelerometerSample& s : source.accelerometer()) {
    if (s.timestamp_s > last_stamp_s + kAccelerometerMarginS) break;
    const Vec3d& a = s.specific_force;
    text += fmt::format("{:.6f} {:.6f} {:.6f} {:.6f}\n", s.timestamp_s, a.x(), a.y(), a.z());
  }
  if (text.empty()) {
    std::error_code ec;
    fs::remove(path, ec);  // a stale file of an earlier sequence written here
    return;
  }
  write_text(path, "# accelerometer data (ddl_slam synth)\n# file: '" + source.config().name +
                       "'\n# timestamp ax ay az\n" + text);
}

struct Lists {
  std::string rgb, depth, assoc, mask, void_mask, bg_rgb, bg_depth, bg_assoc;
  nlohmann::json frames = nlohmann::json::array();
};

void write_indices(const SequenceSource& source, const fs::path& out, const Lists& lists,
                   std::size_t written) {
  const std::string name = source.config().name;
  const std::string file =
      fmt::format("# file: '{}' (ddl_slam synth, seed {})\n", name, source.config().seed);
  write_text((out / "rgb.txt").string(),
             "# color images\n" + file + "# timestamp filename\n" + lists.rgb);
  write_text((out / "depth.txt").string(),
             "# depth maps\n" + file + "# timestamp filename\n" + lists.depth);
  write_text((out / "associations.txt").string(), lists.assoc);
  write_text((out / "dynamic_mask.txt").string(),
             "# dynamic masks (255 = dynamic object visible), one per RGB frame\n" + file +
                 "# timestamp filename\n" + lists.mask);
  if (!source.config().void_boxes_w.empty()) {
    write_text((out / "void_mask.txt").string(),
               "# void masks (255 = not scored: real content of an a-priori dynamic class that is "
               "not part of the dynamic truth), one per RGB frame\n" +
                   file + "# timestamp filename\n" + lists.void_mask);
  }
  write_text(
      (out / "background" / "rgb.txt").string(),
      "# color images without dynamic objects\n" + file + "# timestamp filename\n" + lists.bg_rgb);
  write_text(
      (out / "background" / "depth.txt").string(),
      "# depth maps without dynamic objects\n" + file + "# timestamp filename\n" + lists.bg_depth);
  write_text((out / "background" / "associations.txt").string(), lists.bg_assoc);

  io::Trajectory gt = source.groundtruth();
  if (source.config().background_dir.empty()) gt.resize(std::min(gt.size(), written));
  io::write_tum_trajectory((out / "groundtruth.txt").string(), gt,
                           "ground truth trajectory (T_w_c)\n# file: '" + name + "'");
  write_accelerometer(source, (out / "accelerometer.txt").string(),
                      gt.empty() ? 0.0 : gt.back().timestamp_s);
  write_text((out / "camera.yaml").string(), camera_yaml(source.camera()));

  nlohmann::json meta{{"generator", "ddl_slam synth"},
                      {"name", name},
                      {"seed", source.config().seed},
                      {"frames_written", written},
                      {"settings", source.config().to_json()},
                      {"scene", source.description()},
                      {"conventions",
                       {{"dynamic_mask",
                         "255 where a person, or the movable object from the start of its move "
                         "on, is visible in the RGB frame"},
                        {"void_mask",
                         "255 where a pixel is not scored: real content of an a-priori dynamic "
                         "class (a person sitting in the real sequence) that is not part of the "
                         "dynamic truth; only composites with void boxes write it"},
                        {"background",
                         "the frame rendered without the entities dynamic in it; same sensor "
                         "noise, so RGB equals the frame outside the mask and depth equals it "
                         "outside the mask dilated by 2 px (composite of a camera with "
                         "depth_time_offset_s: outside the people as the depth sensor saw them, "
                         "at its capture instant, dilated by 2 px)"},
                        {"entity_positions",
                         "person: feet (billboard bottom centre) in the "
                         "world frame; object: box centre"}}},
                      {"frames", lists.frames}};
  write_text((out / "meta.json").string(),
             meta.dump(1, ' ', false, nlohmann::json::error_handler_t::replace) + "\n");
}

}  // namespace

std::string format_stamp(double stamp_s) { return fmt::format("{:.6f}", stamp_s); }

double rgb_stamp(const SequenceConfig& config, std::size_t i) {
  const double s =
      config.start_stamp_s + 1e-6 * static_cast<double>(stamp_offset_us(i, config.camera.fps));
  return std::stod(format_stamp(s));
}

double depth_stamp(const SequenceConfig& config, std::size_t i, double rgb_stamp_s) {
  const double u = unit_from_hash(hash3(config.seed, i, 0xd57a));
  const auto jitter_us = std::llround((2.0 * u - 1.0) * config.depth_stamp_jitter_s * 1e6);
  return std::stod(format_stamp(rgb_stamp_s + 1e-6 * static_cast<double>(jitter_us)));
}

std::unique_ptr<SequenceSource> make_sequence_source(const SequenceConfig& config) {
  config.validate();
  if (config.background_dir.empty()) return make_room_sequence(config);
  return make_composite_sequence(config);
}

namespace {

/// True when `dir/meta.json` says write_sequence wrote the folder.
bool written_by_generator(const fs::path& dir) {
  std::ifstream file(dir / "meta.json");
  if (!file) return false;
  try {
    const nlohmann::json meta = nlohmann::json::parse(file);
    return meta.is_object() && meta.value("generator", "") == "ddl_slam synth";
  } catch (const nlohmann::json::exception&) {
    return false;
  }
}

/// The folder write_sequence may write into: new, empty, or an earlier generated sequence, whose
/// own entries are removed.
void prepare_output_folder(const fs::path& out) {
  std::error_code ec;
  if (!fs::exists(out, ec)) return;
  if (!fs::is_directory(out, ec)) {
    throw InputError::at(out.string(), "exists and is not a folder; give a new or empty folder");
  }
  if (fs::is_empty(out, ec)) return;
  if (!written_by_generator(out)) {
    throw InputError::at(out.string(),
                         "is not empty and holds no sequence written by `ddl_slam synth` "
                         "(meta.json); refusing to write into it: give a new or empty folder");
  }
  for (const char* entry : {"rgb", "depth", "dynamic_mask", "void_mask", "background", "rgb.txt",
                            "depth.txt", "associations.txt", "groundtruth.txt", "dynamic_mask.txt",
                            "void_mask.txt", "accelerometer.txt", "camera.yaml", "meta.json"}) {
    fs::remove_all(out / entry, ec);
    if (ec) {
      throw InputError::at((out / entry).string(),
                           "cannot remove the earlier sequence's entry: " + ec.message());
    }
  }
  spdlog::info("synth: {}: replacing the sequence generated there before", out.string());
}

}  // namespace

void write_sequence(const SequenceSource& source, const std::string& out_dir,
                    const WriteOptions& options) {
  const fs::path out(out_dir);
  prepare_output_folder(out);
  const bool with_void = !source.config().void_boxes_w.empty();
  for (const char* sub :
       {"rgb", "depth", "dynamic_mask", "void_mask", "background/rgb", "background/depth"}) {
    if (!with_void && std::string(sub) == "void_mask") continue;
    create_folder(out / sub, "the sequence's images");
  }
  Lists lists;
  const std::size_t total = source.frame_count();
  const int level = options.png_compression;
  // Pipeline: frame i+1 renders while frame i's PNGs are encoded by two tasks (the frame's own
  // images and its background). File contents do not depend on the overlap, only the wall time.
  std::future<void> pending[2];
  std::size_t written = 0;
  auto finish_pending = [&] {
    for (auto& p : pending) {
      if (p.valid()) p.get();
    }
  };
  for (std::size_t i = 0; i < total; ++i) {
    if (options.stop != nullptr && options.stop->load()) {
      finish_pending();
      write_indices(source, out, lists, written);
      throw Interrupted();
    }
    auto frame = std::make_shared<FrameData>(source.render_frame(i));
    const std::string rs = format_stamp(frame->rgb_stamp_s);
    const std::string ds = format_stamp(frame->depth_stamp_s);
    const std::string rgb_rel = "rgb/" + rs + ".png";
    const std::string depth_rel = "depth/" + ds + ".png";
    const std::string mask_rel = "dynamic_mask/" + rs + ".png";
    lists.rgb += rs + " " + rgb_rel + "\n";
    lists.depth += ds + " " + depth_rel + "\n";
    lists.assoc += rs + " " + rgb_rel + " " + ds + " " + depth_rel + "\n";
    lists.mask += rs + " " + mask_rel + "\n";
    const std::string void_rel = "void_mask/" + rs + ".png";
    if (with_void) lists.void_mask += rs + " " + void_rel + "\n";
    lists.bg_rgb += rs + " " + rgb_rel + "\n";
    lists.bg_depth += ds + " " + depth_rel + "\n";
    lists.bg_assoc += rs + " " + rgb_rel + " " + ds + " " + depth_rel + "\n";
    nlohmann::json entities = nlohmann::json::array();
    for (const auto& e : frame->entities) {
      entities.push_back({{"entity", e.entity},
                          {"kind", e.kind},
                          {"visible", e.visible},
                          {"dynamic", e.dynamic},
                          {"position_w", {e.position_w.x(), e.position_w.y(), e.position_w.z()}}});
    }
    lists.frames.push_back({{"index", i},
                            {"rgb_stamp", rs},
                            {"depth_stamp", ds},
                            {"dynamic_fraction", frame->dynamic_fraction},
                            {"entities", entities}});
    finish_pending();
    if (with_void && frame->void_mask.empty()) {
      throw Error("composite source with void boxes returned no void mask for frame " +
                  std::to_string(i));
    }
    pending[0] = std::async(std::launch::async,
                            [frame, out, rgb_rel, depth_rel, mask_rel, void_rel, with_void, level] {
                              write_png((out / rgb_rel).string(), frame->rgb, level);
                              write_png((out / depth_rel).string(), frame->depth_raw, level);
                              write_png((out / mask_rel).string(), frame->dynamic_mask, level);
                              if (with_void)
                                write_png((out / void_rel).string(), frame->void_mask, level);
                            });
    pending[1] = std::async(std::launch::async, [frame, out, rgb_rel, depth_rel, level] {
      write_png((out / "background" / rgb_rel).string(), frame->background_rgb, level);
      write_png((out / "background" / depth_rel).string(), frame->background_depth_raw, level);
    });
    ++written;
    if (options.progress) options.progress(written, total);
  }
  finish_pending();
  write_indices(source, out, lists, written);
}

}  // namespace ddl::synthetic
