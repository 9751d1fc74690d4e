#include "ddl/io/text_table.h"

#include <fmt/format.h>

#include <cerrno>
#include <cstdlib>
#include <filesystem>
#include <fstream>

#include "ddl/core/error.h"

namespace ddl::io {

std::vector<TextRow> read_text_table(const std::string& path) {
  if (!std::filesystem::exists(path)) throw InputError::at(path, "file not found");
  if (std::filesystem::is_directory(path)) throw InputError::at(path, "is a directory, not a file");
  std::ifstream file(path);
  if (!file) throw InputError::at(path, "cannot open for reading");
  std::vector<TextRow> rows;
  std::string text;
  std::size_t line_no = 0;
  while (std::getline(file, text)) {
    ++line_no;
    // A byte-order mark (an editor's UTF-8 with BOM) would make a first "#" comment a data line.
    if (line_no == 1 && text.rfind("\xEF\xBB\xBF", 0) == 0) text.erase(0, 3);
    if (!text.empty() && text.back() == '\r') text.pop_back();
    if (text.empty() || text[0] == '#') continue;
    TextRow row;
    row.line = line_no;
    std::string field;
    for (char c : text) {
      if (c == ' ' || c == '\t' || c == ',') {
        if (!field.empty()) row.fields.push_back(std::move(field));
        field.clear();
      } else {
        field.push_back(c);
      }
    }
    if (!field.empty()) row.fields.push_back(std::move(field));
    if (!row.fields.empty()) rows.push_back(std::move(row));
  }
  if (file.bad()) throw InputError::at(path, "read error");
  return rows;
}

double parse_double(const std::string& text, const std::string& path, std::size_t line) {
  errno = 0;
  char* end = nullptr;
  const double value = std::strtod(text.c_str(), &end);
  if (text.empty() || end != text.c_str() + text.size()) {
    throw InputError::at_line(path, line, fmt::format("'{}' is not a number", text));
  }
  if (errno == ERANGE && std::abs(value) > 1.0) {
    throw InputError::at_line(path, line, fmt::format("'{}' is out of range", text));
  }
  return value;
}

}  // namespace ddl::io
