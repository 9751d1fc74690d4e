// Linked into every test executable. Under ThreadSanitizer, OpenCV runs its parallel loops on the
// calling thread. Its parallel backend here is TBB, which is not instrumented: TSan cannot see
// the joins of cv::parallel_for_ and reports the hand-off between a worker's writes and the
// caller's later reads as a race (15 reports in DenseMapper.*, over 160 in LoopClosure.* at stop
// 20, all inside parallel_for_ bodies). The application runs OpenCV on one thread too
// (dynamic.segmentation.num_threads), so the tests then run as it does; races between the
// project's own threads are still reported.

#include <opencv2/core/utility.hpp>

#if defined(__SANITIZE_THREAD__)
namespace {
const bool kOpenCvSerial = [] {
  cv::setNumThreads(1);
  return true;
}();
}  // namespace
#endif
