#pragma once
// Human-readable and machine-readable reports of an evaluation. The JSON keys mirror the
// reference file shared/reference/eval/*.expected.json ("ate", "rpe") and add "tracked",
// "alignment", "inputs" and "method"; docs/evaluation.md documents the schema.

#include <nlohmann/json.hpp>
#include <string>

#include "ddl/eval/evaluate.h"

namespace ddl::eval {

/// A plain-text table (ATE, RPE, tracked ratio, alignment) for a terminal.
std::string format_report(const EvalResult& result);

nlohmann::json to_json(const EvalResult& result);

/// Writes to_json(result) indented, creating parent folders. Throws ddl::InputError naming the
/// file if it cannot be written.
void write_json_report(const std::string& path, const EvalResult& result);

}  // namespace ddl::eval
