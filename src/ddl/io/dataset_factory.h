#pragma once
// One entry point that opens any supported RGB-D sequence folder behind the DatasetReader
// interface. YAML is never read here (ARCHITECTURE.md section 4): the caller passes an already
// loaded camera. The default camera of a folder is chosen by default_camera_for(), which returns a
// name or path for config::load_camera(); config::resolve_dataset_camera() does both steps.
//
// Typical use (an app):
//   io::DatasetOptions options;
//   options.camera = config::resolve_dataset_camera(dir, camera_flag, options.kind);
//   std::unique_ptr<io::DatasetReader> reader = io::open_dataset(dir, options);
//
// Threads: free functions, callable from any thread; they touch only the file system.

#include <memory>
#include <optional>
#include <string>

#include "ddl/camera/pinhole_camera.h"
#include "ddl/io/dataset_reader.h"
#include "ddl/io/tum_dataset.h"

namespace ddl::io {

enum class DatasetKind {
  kAuto,  // Bonn when the folder name starts with "rgbd_bonn_", otherwise TUM
  kTum,   // TUM RGB-D layout (also synthetic sequences written in that layout)
  kBonn,  // Bonn RGB-D Dynamic dataset (TUM layout, Bonn camera)
};

/// Parses "auto" | "tum" | "bonn"; throws ddl::ConfigError naming `key` otherwise.
DatasetKind parse_dataset_kind(const std::string& text, const std::string& key = "dataset.kind");
std::string to_string(DatasetKind kind);

/// The kind of the folder from its name (never kAuto).
DatasetKind detect_dataset_kind(const std::string& dir);

/// The camera to use when the user names none, as an argument for config::load_camera():
///   kind kBonn, or folder name rgbd_bonn_*   -> "bonn"
///   folder name rgbd_dataset_freiburg1_*     -> "tum1" (freiburg2 -> "tum2", freiburg3 -> "tum3")
///   otherwise <dir>/camera.yaml when present -> that path
/// Throws ddl::InputError naming the folder when it does not exist, or, telling the user to pass
/// --camera, when none of the rules applies.
std::string default_camera_for(const std::string& dir, DatasetKind kind = DatasetKind::kAuto);

struct DatasetOptions {
  DatasetKind kind = DatasetKind::kAuto;        // reader to use
  std::optional<camera::PinholeCamera> camera;  // required: calibration of the stored images
  SequenceOptions sequence;                     // associations, max_difference, file checks

  /// Throws ddl::ConfigError naming the key when a value is invalid or the camera is missing.
  void validate() const;
};

/// Opens the sequence folder `dir`. Throws ddl::InputError (files) or ddl::ConfigError (options).
std::unique_ptr<DatasetReader> open_dataset(const std::string& dir, const DatasetOptions& options);

}  // namespace ddl::io
