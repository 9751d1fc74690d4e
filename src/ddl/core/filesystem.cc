#include "ddl/core/filesystem.h"

#include <fmt/format.h>

#include <cerrno>
#include <cstring>
#include <fstream>
#include <system_error>

#include "ddl/core/error.h"

namespace ddl {

void create_folder(const std::filesystem::path& folder, std::string_view what) {
  std::error_code ec;
  std::filesystem::create_directories(folder, ec);
  // create_directories reports no error for an existing path that is a file.
  if (!ec && std::filesystem::is_directory(folder, ec)) return;
  const std::string reason = ec ? ec.message() : "it exists and is not a folder";
  throw OutputError::at(folder.string(),
                        fmt::format("cannot create the folder for {}: {}", what, reason));
}

void create_parent_folder(const std::filesystem::path& file, std::string_view what) {
  if (file.has_parent_path()) create_folder(file.parent_path(), what);
}

void write_file_atomically(const std::filesystem::path& file, std::string_view what,
                           const std::function<bool(std::ostream&)>& write, bool binary) {
  create_parent_folder(file, what);
  // A device or a pipe (/dev/stdout, /dev/full, a FIFO) is written into, never replaced; so is a
  // symbolic link's target (renaming would replace the link).
  std::error_code status_error;
  const auto status = std::filesystem::symlink_status(file, status_error);
  const bool special = std::filesystem::exists(status) &&
                       !std::filesystem::is_regular_file(status) &&
                       !std::filesystem::is_directory(status);
  std::filesystem::path partial = file;
  if (!special) partial += ".partial";
  const auto discard_partial = [&] {
    std::error_code ignored;
    if (!special) std::filesystem::remove(partial, ignored);
  };
  const auto fail = [&](const std::string& why) {
    discard_partial();
    return OutputError::at(file.string(), fmt::format("cannot write {}: {}", what, why));
  };
  {
    errno = 0;
    std::ofstream out(partial, binary ? std::ios::binary | std::ios::trunc : std::ios::trunc);
    if (!out) {
      // libstdc++ leaves open(2)'s errno: the reason (no permission, no space, read-only).
      throw fail("cannot open " + partial.string() +
                 (errno != 0 ? std::string(": ") + std::strerror(errno) : std::string()));
    }
    bool ok = false;
    try {
      ok = write(out);
    } catch (...) {
      out.close();
      discard_partial();
      throw;
    }
    out.close();  // flushes: a small file's write error shows only here
    if (!ok || out.fail()) throw fail("write failed (disk full?)");
  }
  if (special) return;
  std::error_code ec;
  std::filesystem::rename(partial, file, ec);
  if (ec) throw fail("cannot rename " + partial.string() + ": " + ec.message());
}

void write_file_atomically(const std::filesystem::path& file, std::string_view what,
                           std::string_view contents) {
  write_file_atomically(
      file, what,
      [&](std::ostream& out) {
        out.write(contents.data(), static_cast<std::streamsize>(contents.size()));
        return true;
      },
      true);
}

}  // namespace ddl
