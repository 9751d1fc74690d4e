#include "ddl/synthetic/png_writer.h"

#include <fmt/format.h>
#include <zlib.h>

#include <cerrno>
#include <cstring>
#include <fstream>

#include "ddl/core/error.h"

namespace ddl::synthetic {
namespace {

void put_u32(std::vector<unsigned char>& out, std::uint32_t v) {
  out.push_back(static_cast<unsigned char>(v >> 24U));
  out.push_back(static_cast<unsigned char>(v >> 16U));
  out.push_back(static_cast<unsigned char>(v >> 8U));
  out.push_back(static_cast<unsigned char>(v));
}

void put_chunk(std::vector<unsigned char>& out, const char type[4], const unsigned char* data,
               std::size_t size) {
  put_u32(out, static_cast<std::uint32_t>(size));
  const std::size_t start = out.size();
  out.insert(out.end(), type, type + 4);
  if (size > 0) out.insert(out.end(), data, data + size);
  const uLong crc = crc32(0L, out.data() + start, static_cast<uInt>(size + 4));
  put_u32(out, static_cast<std::uint32_t>(crc));
}

}  // namespace

std::vector<unsigned char> encode_png(const cv::Mat& image, int level) {
  const int type = image.type();
  if (type != CV_8UC3 && type != CV_8UC1 && type != CV_16UC1) {
    throw Error("encode_png: expected an 8-bit BGR, 8-bit gray or 16-bit gray image");
  }
  const bool color = type == CV_8UC3;
  const int bytes_per_pixel = static_cast<int>(image.elemSize());
  const std::size_t row_bytes = static_cast<std::size_t>(image.cols) * bytes_per_pixel;
  // Filtered scanlines: a filter byte, then the row in PNG byte order (RGB, big-endian 16-bit).
  std::vector<unsigned char> raw((row_bytes + 1) * static_cast<std::size_t>(image.rows));
  std::vector<unsigned char> previous(row_bytes, 0);
  std::vector<unsigned char> current(row_bytes);
  for (int y = 0; y < image.rows; ++y) {
    const unsigned char* src = image.ptr<unsigned char>(y);
    if (color) {
      for (int x = 0; x < image.cols; ++x) {
        current[3 * x] = src[3 * x + 2];
        current[3 * x + 1] = src[3 * x + 1];
        current[3 * x + 2] = src[3 * x];
      }
    } else if (type == CV_16UC1) {
      const auto* src16 = image.ptr<std::uint16_t>(y);
      for (int x = 0; x < image.cols; ++x) {
        current[2 * x] = static_cast<unsigned char>(src16[x] >> 8U);
        current[2 * x + 1] = static_cast<unsigned char>(src16[x] & 0xffU);
      }
    } else {
      std::memcpy(current.data(), src, row_bytes);
    }
    unsigned char* dst = &raw[static_cast<std::size_t>(y) * (row_bytes + 1)];
    if (color) {
      dst[0] = 2;  // Up: difference to the row above
      for (std::size_t i = 0; i < row_bytes; ++i) {
        dst[1 + i] = static_cast<unsigned char>(current[i] - previous[i]);
      }
      previous.swap(current);
    } else {
      dst[0] = 0;  // None
      std::memcpy(dst + 1, current.data(), row_bytes);
    }
  }
  z_stream z{};
  if (deflateInit2(&z, level, Z_DEFLATED, 15, 8, color ? Z_HUFFMAN_ONLY : Z_DEFAULT_STRATEGY) !=
      Z_OK) {
    throw Error("encode_png: zlib initialisation failed");
  }
  std::vector<unsigned char> compressed(deflateBound(&z, static_cast<uLong>(raw.size())));
  z.next_in = raw.data();
  z.avail_in = static_cast<uInt>(raw.size());
  z.next_out = compressed.data();
  z.avail_out = static_cast<uInt>(compressed.size());
  const int rc = deflate(&z, Z_FINISH);
  const std::size_t compressed_size = z.total_out;
  deflateEnd(&z);
  if (rc != Z_STREAM_END) throw Error("encode_png: zlib compression failed");

  std::vector<unsigned char> out = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
  std::vector<unsigned char> header;
  put_u32(header, static_cast<std::uint32_t>(image.cols));
  put_u32(header, static_cast<std::uint32_t>(image.rows));
  header.push_back(type == CV_16UC1 ? 16 : 8);  // bit depth
  header.push_back(color ? 2 : 0);              // colour type: truecolour / grayscale
  header.push_back(0);                          // deflate
  header.push_back(0);                          // adaptive filtering (per-row filter bytes)
  header.push_back(0);                          // no interlace
  put_chunk(out, "IHDR", header.data(), header.size());
  put_chunk(out, "IDAT", compressed.data(), compressed_size);
  put_chunk(out, "IEND", nullptr, 0);
  return out;
}

void write_png_file(const std::string& path, const cv::Mat& image, int level) {
  const std::vector<unsigned char> bytes = encode_png(image, level);
  std::ofstream file(path, std::ios::binary | std::ios::trunc);
  file.write(reinterpret_cast<const char*>(bytes.data()),
             static_cast<std::streamsize>(bytes.size()));
  file.flush();
  if (!file) {
    throw OutputError::at(path, fmt::format("cannot write the image: {}", std::strerror(errno)));
  }
}

}  // namespace ddl::synthetic
