#pragma once
// Reading the whitespace-separated text lists of the TUM format (rgb.txt, depth.txt,
// associations.txt, groundtruth.txt, trajectories): '#' starts a comment line, fields are
// separated by spaces, tabs or commas (as TUM's scripts accept), blank lines are skipped.

#include <cstddef>
#include <string>
#include <vector>

namespace ddl::io {

struct TextRow {
  std::size_t line = 0;             // 1-based line number in the file
  std::vector<std::string> fields;  // non-empty fields
};

/// Throws ddl::InputError naming the file when it is missing or unreadable.
std::vector<TextRow> read_text_table(const std::string& path);

/// Parses a whole field as a double (Python float() semantics for decimal input; "nan" accepted).
/// Throws ddl::InputError naming file, line and the offending text.
double parse_double(const std::string& text, const std::string& path, std::size_t line);

}  // namespace ddl::io
