#include "ddl/core/binary_file.h"

#include <fcntl.h>
#include <fmt/format.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include <bit>
#include <cerrno>
#include <cstring>

#include "ddl/core/error.h"

namespace ddl {
namespace {

static_assert(std::endian::native == std::endian::little,
              "the project's binary files are little-endian; add byte swapping for this platform");

std::uint64_t mix(std::uint64_t x) { return std::rotl(x * 0x9E3779B97F4A7C15ull, 31); }

std::uint64_t word_at(const unsigned char* p) {
  std::uint64_t value;
  std::memcpy(&value, p, sizeof(value));
  return value;
}

}  // namespace

std::uint64_t checksum64(const unsigned char* data, std::size_t size) {
  std::uint64_t lanes[4] = {0x243F6A8885A308D3ull, 0x13198A2E03707344ull, 0xA4093822299F31D0ull,
                            0x082EFA98EC4E6C89ull};
  const std::size_t words = size / 8;
  std::size_t i = 0;
  for (; i + 4 <= words; i += 4) {
    for (std::size_t l = 0; l < 4; ++l) lanes[l] = mix(lanes[l] ^ word_at(data + 8 * (i + l)));
  }
  for (; i < words; ++i) lanes[0] = mix(lanes[0] ^ word_at(data + 8 * i));
  std::uint64_t h = size;
  for (std::uint64_t lane : lanes) h = mix(h ^ lane);
  return h;
}

MappedFile::MappedFile(const std::string& path) {
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) throw InputError::at(path, fmt::format("cannot open: {}", std::strerror(errno)));
  struct stat st {};
  if (::fstat(fd, &st) != 0) {
    const std::string reason = std::strerror(errno);
    ::close(fd);
    throw InputError::at(path, fmt::format("cannot stat: {}", reason));
  }
  if (!S_ISREG(st.st_mode)) {
    ::close(fd);
    throw InputError::at(path, "not a regular file");
  }
  size_ = static_cast<std::size_t>(st.st_size);
  if (size_ > 0) {
    void* p = ::mmap(nullptr, size_, PROT_READ, MAP_PRIVATE | MAP_POPULATE, fd, 0);
    if (p == MAP_FAILED) {
      const std::string reason = std::strerror(errno);
      ::close(fd);
      throw InputError::at(path, fmt::format("cannot map: {}", reason));
    }
    data_ = static_cast<const unsigned char*>(p);
  }
  ::close(fd);
}

MappedFile::~MappedFile() {
  if (data_ != nullptr) ::munmap(const_cast<unsigned char*>(data_), size_);
}

}  // namespace ddl
