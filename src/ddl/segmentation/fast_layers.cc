#include "ddl/segmentation/fast_layers.h"

#include <mutex>
#include <opencv2/dnn.hpp>

#include "ddl/segmentation/block_permute_layer.h"
#include "ddl/segmentation/corner_resize_layer.h"

namespace ddl::segmentation {

void register_fast_layers() {
  static std::once_flag once;
  std::call_once(once, [] {
    cv::dnn::LayerFactory::registerLayer("Permute", BlockPermuteLayer::create);
    cv::dnn::LayerFactory::registerLayer("Resize", CornerResizeLayer::create);
  });
}

}  // namespace ddl::segmentation
