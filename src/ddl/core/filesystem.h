#pragma once
// Output folders: created with their parents, or an InputError that names the folder, what it
// was for and why it could not be created (a file in the way, no permission), so that every
// writer reports the same failure the same way.

#include <filesystem>
#include <string_view>

namespace ddl {

/// Creates `folder` and its missing parents; nothing when it is already a folder. Throws
/// InputError naming `folder` and `what` it is for when it cannot be created or exists as
/// something other than a folder.
void create_folder(const std::filesystem::path& folder, std::string_view what);

/// Creates the folder that will hold the file `file` (nothing when the path names no folder).
void create_parent_folder(const std::filesystem::path& file, std::string_view what);

}  // namespace ddl
