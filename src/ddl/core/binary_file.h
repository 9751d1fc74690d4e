#pragma once
// Helpers of the project's binary files (vocabulary, sparse map): a checksum that detects
// corruption and a whole-file read. They are written with write_file_atomically
// (core/filesystem.h). Pure functions: thread-safe.

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace ddl {

/// Detects corruption (not tampering): four independent multiply-rotate lanes over 64-bit
/// little-endian words, each step a bijection of the lane state, so any single changed word
/// changes the result. `size` must be a multiple of 8 (trailing bytes are not read).
std::uint64_t checksum64(const unsigned char* data, std::size_t size);

/// The whole file. Throws ddl::InputError naming the file when it cannot be read or is not a
/// regular file.
std::vector<unsigned char> read_whole_file(const std::string& path);

}  // namespace ddl
