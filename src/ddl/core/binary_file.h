#pragma once
// Helpers of the project's binary files (vocabulary, sparse map): a checksum that detects
// corruption and a read-only memory map of a whole file. They are written with
// write_file_atomically (core/filesystem.h). checksum64 is a pure function; a MappedFile is
// immutable after construction (thread-safe to read).

#include <cstddef>
#include <cstdint>
#include <string>

namespace ddl {

/// Detects corruption (not tampering): four independent multiply-rotate lanes over 64-bit
/// little-endian words, each step a bijection of the lane state, so any single changed word
/// changes the result. `size` must be a multiple of 8 (trailing bytes are not read).
std::uint64_t checksum64(const unsigned char* data, std::size_t size);

/// A read-only memory map of a whole file: the page cache is read in place, with no buffer to
/// allocate and fill (the load cost of a large vocabulary is mostly memory traffic). Throws
/// ddl::InputError naming the file when it cannot be opened or mapped or is not a regular file.
/// An empty file maps to data() == nullptr, size() == 0.
class MappedFile {
 public:
  explicit MappedFile(const std::string& path);
  ~MappedFile();
  MappedFile(const MappedFile&) = delete;
  MappedFile& operator=(const MappedFile&) = delete;
  const unsigned char* data() const { return data_; }
  std::size_t size() const { return size_; }

 private:
  const unsigned char* data_ = nullptr;
  std::size_t size_ = 0;
};

}  // namespace ddl
