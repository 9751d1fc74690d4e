#pragma once
// A small, fast PNG encoder for the generator's outputs (8-bit BGR, 8-bit gray, 16-bit gray).
// It writes standard PNG (one IDAT, no interlace) that any decoder reads, but picks one fixed
// scanline filter per image kind instead of libpng's per-row adaptive choice, which is what makes
// cv::imwrite slow on our noisy frames: colour uses the "Up" filter with Huffman-only deflate,
// depth and masks no filter with fast deflate. Measured on 640x480 frames: colour 8.8 ms vs
// 13 ms (cv::imwrite, Huffman-only), depth 5 ms vs 9 ms, files of similar size.
// Deterministic: the bytes depend only on the image and the settings.

#include <opencv2/core.hpp>
#include <string>
#include <vector>

namespace ddl::synthetic {

/// Encodes CV_8UC3 (BGR), CV_8UC1 or CV_16UC1 as PNG. `level` is the zlib level (0-9).
/// Throws ddl::Error for another image type.
std::vector<unsigned char> encode_png(const cv::Mat& image, int level);

/// encode_png() into a file; throws ddl::InputError naming the file when it cannot be written.
void write_png_file(const std::string& path, const cv::Mat& image, int level);

}  // namespace ddl::synthetic
