// The vocabulary file: a fixed header, the nodes packed in id order, a checksum. Read with one
// fread and decoded with memcpy, so a million-node vocabulary loads in tens of milliseconds.
// Layout (little-endian; docs/vocabulary.md):
//   0  char[8] magic "DDLVOCAB"
//   8  u32     version (1)
//  12  u32     branching k
//  16  u32     levels L
//  20  u32     weighting (0 tf-idf, 1 tf, 2 idf, 3 binary)
//  24  u64     node count N
//  32  u64     descriptor tag (fingerprint of the BRIEF pattern; 0 = not recorded)
//  40  N x 40  nodes: u32 parent (0xFFFFFFFF for the root), u8[32] descriptor, f32 weight
//  40+40N u64  checksum of every preceding byte

#include <fmt/format.h>

#include <bit>
#include <cstring>
#include <memory>

#include "ddl/core/binary_file.h"
#include "ddl/core/error.h"
#include "ddl/core/filesystem.h"
#include "ddl/vocabulary/vocabulary.h"

namespace ddl::vocabulary {
namespace {

static_assert(std::endian::native == std::endian::little,
              "the vocabulary file is little-endian; add byte swapping for this platform");

constexpr char kMagic[8] = {'D', 'D', 'L', 'V', 'O', 'C', 'A', 'B'};
constexpr std::uint32_t kVersion = 1;
constexpr std::size_t kHeaderBytes = 40;
constexpr std::size_t kNodeBytes = 4 + kDescriptorBytes + 4;
constexpr std::size_t kChecksumBytes = 8;

template <typename T>
T read_at(const unsigned char* p) {
  T value;
  std::memcpy(&value, p, sizeof(T));
  return value;
}

template <typename T>
void write_at(unsigned char* p, T value) {
  std::memcpy(p, &value, sizeof(T));
}

}  // namespace

void Vocabulary::save(const std::string& path) const {
  if (empty()) throw Error(fmt::format("{}: refusing to save an empty vocabulary", path));
  const std::size_t n = node_count();
  const std::size_t payload = kHeaderBytes + n * kNodeBytes;
  std::unique_ptr<unsigned char[]> buffer(new unsigned char[payload + kChecksumBytes]);
  unsigned char* p = buffer.get();
  std::memcpy(p, kMagic, sizeof(kMagic));
  write_at<std::uint32_t>(p + 8, kVersion);
  write_at<std::uint32_t>(p + 12, static_cast<std::uint32_t>(branching_));
  write_at<std::uint32_t>(p + 16, static_cast<std::uint32_t>(levels_));
  write_at<std::uint32_t>(p + 20, static_cast<std::uint32_t>(weighting_));
  write_at<std::uint64_t>(p + 24, static_cast<std::uint64_t>(n));
  write_at<std::uint64_t>(p + 32, descriptor_tag_);
  for (std::size_t i = 0; i < n; ++i) {
    unsigned char* q = p + kHeaderBytes + i * kNodeBytes;
    write_at<std::uint32_t>(q, parents_[i]);
    std::memcpy(q + 4, descriptors_[i].data(), kDescriptorBytes);
    write_at<float>(q + 4 + kDescriptorBytes, weights_[i]);
  }
  write_at<std::uint64_t>(p + payload, checksum64(p, payload));

  write_file_atomically(
      path, "the vocabulary",
      std::string_view(reinterpret_cast<const char*>(p), payload + kChecksumBytes));
}

Vocabulary Vocabulary::load(const std::string& path) {
  const MappedFile file(path);
  const std::size_t size = file.size();
  const unsigned char* p = file.data();
  if (size == 0) throw InputError::at(path, "empty file (0 bytes)");
  if (size < sizeof(kMagic)) {
    throw InputError::at(
        path, fmt::format("truncated: {} bytes, shorter than the {}-byte magic \"DDLVOCAB\"", size,
                          sizeof(kMagic)));
  }
  if (std::memcmp(p, kMagic, sizeof(kMagic)) != 0) {
    throw InputError::at(path,
                         "not a DDL-SLAM vocabulary file (wrong magic; expected \"DDLVOCAB\")");
  }
  if (size < kHeaderBytes) {
    throw InputError::at(path, fmt::format("truncated: {} bytes, shorter than the {}-byte header",
                                           size, kHeaderBytes));
  }
  const auto version = read_at<std::uint32_t>(p + 8);
  if (version != kVersion) {
    throw InputError::at(path, fmt::format("unsupported vocabulary file version {} (this build "
                                           "reads version {})",
                                           version, kVersion));
  }
  const auto branching = read_at<std::uint32_t>(p + 12);
  const auto levels = read_at<std::uint32_t>(p + 16);
  const auto weighting_value = read_at<std::uint32_t>(p + 20);
  const auto node_count = read_at<std::uint64_t>(p + 24);
  const std::size_t max_nodes = (size - kHeaderBytes) / kNodeBytes;
  const std::size_t expected =
      node_count <= max_nodes ? kHeaderBytes + node_count * kNodeBytes + kChecksumBytes : 0;
  if (node_count > max_nodes || size != expected) {
    throw InputError::at(
        path, node_count <= max_nodes
                  ? fmt::format("size {} bytes does not match the header's {} nodes "
                                "({} bytes expected): truncated or corrupted",
                                size, node_count, expected)
                  : fmt::format("size {} bytes cannot hold the header's {} nodes (at most {}): "
                                "truncated or corrupted",
                                size, node_count, max_nodes));
  }
  const std::size_t payload = size - kChecksumBytes;
  if (checksum64(p, payload) != read_at<std::uint64_t>(p + payload)) {
    throw InputError::at(path, "checksum mismatch: the file is corrupted");
  }
  if (weighting_value > static_cast<std::uint32_t>(Weighting::kBinary)) {
    throw InputError::at(path, fmt::format("unknown weighting value {}", weighting_value));
  }
  if (branching > 64 || levels > 10) {
    throw InputError::at(path,
                         fmt::format("invalid header: branching {}, levels {}", branching, levels));
  }
  Vocabulary v;
  v.branching_ = static_cast<int>(branching);
  v.levels_ = static_cast<int>(levels);
  v.weighting_ = static_cast<Weighting>(weighting_value);
  v.descriptor_tag_ = read_at<std::uint64_t>(p + 32);
  v.parents_.resize(node_count);
  v.descriptors_.resize(node_count);
  v.weights_.resize(node_count);
  for (std::size_t i = 0; i < node_count; ++i) {
    const unsigned char* q = p + kHeaderBytes + i * kNodeBytes;
    v.parents_[i] = read_at<std::uint32_t>(q);
    std::memcpy(v.descriptors_[i].data(), q + 4, kDescriptorBytes);
    v.weights_[i] = read_at<float>(q + 4 + kDescriptorBytes);
  }
  try {
    v.build_index();
  } catch (const Error& e) {
    throw InputError::at(path, fmt::format("invalid vocabulary: {}", e.what()));
  }
  return v;
}

}  // namespace ddl::vocabulary
