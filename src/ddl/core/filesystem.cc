#include "ddl/core/filesystem.h"

#include <fmt/format.h>

#include <system_error>

#include "ddl/core/error.h"

namespace ddl {

void create_folder(const std::filesystem::path& folder, std::string_view what) {
  std::error_code ec;
  std::filesystem::create_directories(folder, ec);
  // create_directories reports no error for an existing path that is a file.
  if (!ec && std::filesystem::is_directory(folder, ec)) return;
  const std::string reason = ec ? ec.message() : "it exists and is not a folder";
  throw InputError::at(folder.string(),
                       fmt::format("cannot create the folder for {}: {}", what, reason));
}

void create_parent_folder(const std::filesystem::path& file, std::string_view what) {
  if (file.has_parent_path()) create_folder(file.parent_path(), what);
}

}  // namespace ddl
