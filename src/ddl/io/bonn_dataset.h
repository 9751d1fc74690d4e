#pragma once
// Reader for the Bonn RGB-D Dynamic dataset (Palazzolo et al., IROS 2019,
// https://www.ipb.uni-bonn.de/data/rgbd-dynamic-dataset/). Its sequences use the TUM layout
// (rgb.txt, depth.txt, groundtruth.txt, 16-bit depth at 5000 per metre), so this is a TumDataset
// with its own identity; the camera of all sequences is config/cameras/bonn.yaml (pick it with
// io::default_camera_for or config::resolve_dataset_camera).
//
// Ground truth: groundtruth.txt is in the TUM trajectory format and is what trajectory evaluation
// (ATE/RPE) uses, as for TUM. The dataset page additionally documents a fixed transform needed
// only to bring those poses into the frame of its laser-scanned ground-truth point cloud; see
// docs/datasets.md. Threads: as TumDataset (immutable after construction).

#include "ddl/io/tum_dataset.h"

namespace ddl::io {

class BonnDataset : public TumDataset {
 public:
  BonnDataset(const std::string& dir, const camera::PinholeCamera& camera,
              const SequenceOptions& options = {})
      : TumDataset(dir, camera, options) {}
};

}  // namespace ddl::io
