#pragma once
// Faster stand-ins for OpenCV dnn layers, each with the same output bit for bit
// (docs/dynamics.md, "CNN cost"): BlockPermuteLayer for "Permute" (ONNX Transpose) and
// CornerResizeLayer for "Resize" (ONNX Resize). Each computes the float cases it speeds up on
// the CPU target and runs OpenCV's own layer for the rest (other targets, FP16, quantized nets:
// FallbackLayer).
//
// OpenCV creates layers through a process-wide factory, so they are installed there, once per
// process (the only way OpenCV offers to replace a layer); networks set up afterwards use them.
// Thread-safety: may be called from any thread.

namespace ddl::segmentation {

void register_fast_layers();

}  // namespace ddl::segmentation
