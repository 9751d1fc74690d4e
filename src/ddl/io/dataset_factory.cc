#include "ddl/io/dataset_factory.h"

#include <fmt/format.h>

#include <filesystem>

#include "ddl/core/error.h"
#include "ddl/io/bonn_dataset.h"

namespace ddl::io {
namespace fs = std::filesystem;

namespace {

bool starts_with(const std::string& text, const std::string& prefix) {
  return text.rfind(prefix, 0) == 0;
}

}  // namespace

DatasetKind parse_dataset_kind(const std::string& text, const std::string& key) {
  if (text == "auto") return DatasetKind::kAuto;
  if (text == "tum") return DatasetKind::kTum;
  if (text == "bonn") return DatasetKind::kBonn;
  throw ConfigError::for_key(key, fmt::format("'{}' is not one of auto, tum, bonn", text));
}

std::string to_string(DatasetKind kind) {
  switch (kind) {
    case DatasetKind::kAuto:
      return "auto";
    case DatasetKind::kTum:
      return "tum";
    case DatasetKind::kBonn:
      return "bonn";
  }
  return "?";
}

DatasetKind detect_dataset_kind(const std::string& dir) {
  return starts_with(sequence_name(dir), "rgbd_bonn_") ? DatasetKind::kBonn : DatasetKind::kTum;
}

std::string default_camera_for(const std::string& dir, DatasetKind kind) {
  const std::string name = sequence_name(dir);
  std::error_code ec;
  require_sequence_folder(dir);
  if (kind == DatasetKind::kBonn || starts_with(name, "rgbd_bonn_")) return "bonn";
  if (starts_with(name, "rgbd_dataset_freiburg1_")) return "tum1";
  if (starts_with(name, "rgbd_dataset_freiburg2_")) return "tum2";
  if (starts_with(name, "rgbd_dataset_freiburg3_")) return "tum3";
  const fs::path own = fs::path(dir) / "camera.yaml";
  if (fs::is_regular_file(own, ec)) return own.string();
  throw InputError::at(
      dir, fmt::format("cannot tell which camera recorded this sequence: the folder name '{}' is "
                       "neither rgbd_dataset_freiburg{{1,2,3}}_* nor rgbd_bonn_*, and there is no "
                       "camera.yaml in it; pass --camera tum1|tum2|tum3|bonn|synthetic|FILE.yaml",
                       name));
}

void DatasetOptions::validate() const {
  if (!camera) {
    throw ConfigError::for_key("camera",
                               "no camera given for the dataset (load one with "
                               "config::load_camera or config::resolve_dataset_camera)");
  }
  camera->validate();
  sequence.validate();
}

std::unique_ptr<DatasetReader> open_dataset(const std::string& dir, const DatasetOptions& options) {
  options.validate();
  const DatasetKind kind =
      options.kind == DatasetKind::kAuto ? detect_dataset_kind(dir) : options.kind;
  if (kind == DatasetKind::kBonn) {
    return std::make_unique<BonnDataset>(dir, *options.camera, options.sequence);
  }
  return std::make_unique<TumDataset>(dir, *options.camera, options.sequence);
}

}  // namespace ddl::io
