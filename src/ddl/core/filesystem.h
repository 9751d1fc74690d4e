#pragma once
// Output folders: created with their parents, or an OutputError that names the folder, what it
// was for and why it could not be created (a file in the way, no permission), so that every
// writer reports the same failure the same way.

#include <filesystem>
#include <functional>
#include <ostream>
#include <string_view>

namespace ddl {

/// Creates `folder` and its missing parents; nothing when it is already a folder. Throws
/// OutputError naming `folder` and `what` it is for when it cannot be created or exists as
/// something other than a folder.
void create_folder(const std::filesystem::path& folder, std::string_view what);

/// Creates the folder that will hold the file `file` (nothing when the path names no folder).
void create_parent_folder(const std::filesystem::path& file, std::string_view what);

/// Writes `file` whole or not at all: `write` fills a temporary file beside it (`<name>.partial`),
/// which is closed, checked and then renamed onto `file`. A reader (or a run interrupted
/// mid-write) never sees a half-written file: a failed write leaves the previous `file`, if any,
/// and removes the temporary one. An existing file that is neither a regular file nor a folder (a
/// device such as /dev/full, a FIFO, a symbolic link) is written into directly, never replaced.
/// `write` returning false counts as a failed write. Creates the parent folder (OutputError as
/// create_parent_folder); throws OutputError naming `file` and `what` it is when it cannot be
/// opened, written or renamed.
void write_file_atomically(const std::filesystem::path& file, std::string_view what,
                           const std::function<bool(std::ostream&)>& write, bool binary = false);

/// The same for contents already in memory (text, or an encoded image), written as they are.
void write_file_atomically(const std::filesystem::path& file, std::string_view what,
                           std::string_view contents);

}  // namespace ddl
