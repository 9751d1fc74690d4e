#include "ddl/eval/benchmark_tables.h"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

namespace ddl::eval {
namespace {

using nlohmann::json;

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

json number(double v) { return std::isfinite(v) ? json(v) : json(nullptr); }

double value_at(const json& j, const json::json_pointer& p) {
  if (!j.is_object() || !j.contains(p)) return kNaN;
  const json& v = j.at(p);
  return v.is_number() ? v.get<double>() : kNaN;
}

/// One error table: where its statistics are in summary.json.
struct ErrorTable {
  const char* key;                    // key in tables.json
  const char* title;                  // Markdown heading
  const char* unit;                   // of the statistics
  const char* object;                 // under summary["evaluation"]
  std::array<const char*, 4> fields;  // rmse, mean, median, std
};

constexpr std::array<const char*, 4> kStats = {"rmse", "mean", "median", "std"};

constexpr std::array<ErrorTable, 3> kErrorTables = {{
    {"ate",
     "Table 1: absolute trajectory error (ATE)",
     "m",
     "ate",
     {"rmse_m", "mean_m", "median_m", "std_m"}},
    {"rpe_translation",
     "Table 2: relative pose error, translational (RPE)",
     "m/s",
     "rpe",
     {"trans_rmse_m_per_s", "trans_mean_m_per_s", "trans_median_m_per_s", "trans_std_m_per_s"}},
    {"rpe_rotation",
     "Table 3: relative pose error, rotational (RPE)",
     "deg/s",
     "rpe",
     {"rot_rmse_deg_per_s", "rot_mean_deg_per_s", "rot_median_deg_per_s", "rot_std_deg_per_s"}},
}};

constexpr std::array<const char*, 4> kMaskSources = {"cnn", "geometry", "free_space", "combined"};

json error_stats(const json& summary, const ErrorTable& table) {
  json out = json::object();
  for (std::size_t i = 0; i < kStats.size(); ++i) {
    out[kStats[i]] = number(value_at(
        summary,
        json::json_pointer(fmt::format("/evaluation/{}/{}", table.object, table.fields[i]))));
  }
  return out;
}

double as_double(const json& v) { return v.is_number() ? v.get<double>() : kNaN; }

json tracking_entry(const json& summary) {
  if (!summary.is_object()) return nullptr;
  // Frames with a pose in the trajectory, which the ratio beside it also counts; a map reset
  // drops the poses before it ("poses"). Summaries written before 2026-11-27 have only the
  // frames tracked when they were processed.
  json tracked = nullptr;
  if (summary.contains("/statistics/poses"_json_pointer)) {
    tracked = summary["statistics"]["poses"];
  } else if (summary.contains("/statistics/frames_tracked"_json_pointer)) {
    tracked = summary["statistics"]["frames_tracked"];
  }
  return {{"frames_processed", summary.value("frames_processed", json(nullptr))},
          {"frames_tracked", tracked},
          {"frames_lost", summary.contains("/statistics/frames_lost"_json_pointer)
                              ? summary["statistics"]["frames_lost"]
                              : json(nullptr)},
          {"tracked_ratio", number(value_at(summary, "/evaluation/tracked_ratio"_json_pointer))},
          {"wall_time_s", number(value_at(summary, "/wall_time_s"_json_pointer))},
          {"interrupted", summary.value("interrupted", false)},
          {"failed", summary.value("failed", false)}};
}

std::string cell(const json& v, const char* format = "{:.4f}") {
  if (!v.is_number()) return "-";
  return fmt::format(fmt::runtime(format), v.get<double>());
}

/// An error statistic in fixed notation with at least 4 decimals and at least 3 significant
/// digits: sub-millimetre ATEs keep their digits (0.000854, not 0.0009, whose rounding hid the
/// improvement percentages next to them; review, stop 32).
std::string error_cell(const json& v) {
  if (!v.is_number()) return "-";
  const double x = v.get<double>();
  int decimals = 4;
  if (std::isfinite(x) && x != 0.0) {
    const int magnitude = static_cast<int>(std::floor(std::log10(std::abs(x))));
    decimals = std::clamp(2 - magnitude, 4, 9);
  }
  return fmt::format("{:.{}f}", x, decimals);
}

std::string count_cell(const json& v) {
  return v.is_number_integer() ? std::to_string(v.get<long long>()) : "-";
}

}  // namespace

double improvement_percent(double baseline, double ours) {
  if (!std::isfinite(baseline) || !std::isfinite(ours) || baseline == 0.0) return kNaN;
  return (baseline - ours) / baseline * 100.0;
}

json benchmark_tables(const std::vector<BenchmarkRow>& rows, const json& settings,
                      const json& skipped) {
  json t;
  t["settings"] = settings;
  t["columns"] = {{"baseline", "ORB-SLAM2: the SLAM core without dynamic removal (--no-dynamic)"},
                  {"ours", "DDL-SLAM: with dynamic removal"},
                  {"improvement_pct", "(baseline - ours) / baseline * 100"}};
  t["sequences"] = json::array();
  for (const BenchmarkRow& row : rows) t["sequences"].push_back(row.sequence);

  for (const ErrorTable& table : kErrorTables) {
    json& out = t[table.key];
    out["title"] = table.title;
    out["unit"] = table.unit;
    out["rows"] = json::array();
    for (const BenchmarkRow& row : rows) {
      json r = {{"sequence", row.sequence},
                {"baseline", error_stats(row.baseline, table)},
                {"ours", error_stats(row.ours, table)}};
      for (const char* stat : kStats) {
        r["improvement_pct"][stat] =
            number(improvement_percent(as_double(r["baseline"][stat]), as_double(r["ours"][stat])));
      }
      out["rows"].push_back(r);
    }
  }

  t["masks"] = json::array();
  for (const BenchmarkRow& row : rows) {
    if (!row.ours.is_object() || !row.ours.contains("masks")) continue;
    const json& m = row.ours["masks"];
    json r = {{"sequence", row.sequence}};
    for (const char* source : kMaskSources) {
      const json& s = m.value(source, json::object());
      r[source] = {
          {"mean_iou", s.value("mean_iou", json(nullptr))},
          {"precision", s.value("precision", json(nullptr))},
          {"recall", s.value("recall", json(nullptr))},
          {"frames", s.value("frames", json(nullptr))},
          {"dynamic_frames", s.value("dynamic_frames", json(nullptr))},
          {"static_frames", s.value("static_frames", json(nullptr))},
          {"static_false_positive_px", s.value("static_false_positive_px", json(nullptr))}};
    }
    r["moved_object"] = m.contains("moved_object") ? m["moved_object"] : json(nullptr);
    t["masks"].push_back(r);
  }

  t["tracking"] = json::array();
  for (const BenchmarkRow& row : rows) {
    t["tracking"].push_back({{"sequence", row.sequence},
                             {"baseline", tracking_entry(row.baseline)},
                             {"ours", tracking_entry(row.ours)}});
  }
  t["skipped"] = skipped.is_array() ? skipped : json::array();
  return t;
}

std::string benchmark_tables_markdown(const json& tables) {
  std::string md = "# Benchmark: ORB-SLAM2 column (no dynamic removal) vs DDL-SLAM\n\n";
  const json& settings = tables.value("settings", json::object());
  if (!settings.empty()) {
    md += "Settings:";
    for (const auto& [key, value] : settings.items()) {
      md += fmt::format(" {} `{}`;", key,
                        value.is_string() ? value.get<std::string>() : value.dump());
    }
    md += "\n\n";
  }
  md += "Improvement = (ORB-SLAM2 - DDL-SLAM) / ORB-SLAM2 x 100 (positive: DDL-SLAM better).\n";

  for (const ErrorTable& table : kErrorTables) {
    const json& t = tables.at(table.key);
    md += fmt::format("\n## {} ({})\n\n", table.title, table.unit);
    md +=
        "| sequence | ORB-SLAM2 RMSE | Mean | Median | S.D. | DDL-SLAM RMSE | Mean | Median | "
        "S.D. | Improvement RMSE | Mean | Median | S.D. |\n";
    md += "| --- |";
    for (int i = 0; i < 12; ++i) md += " ---: |";
    md += "\n";
    for (const json& r : t.at("rows")) {
      md += "| " + r.at("sequence").get<std::string>() + " |";
      for (const char* column : {"baseline", "ours"}) {
        for (const char* stat : kStats) md += fmt::format(" {} |", error_cell(r[column][stat]));
      }
      for (const char* stat : kStats) {
        md += fmt::format(" {} |", cell(r["improvement_pct"][stat], "{:.2f}%"));
      }
      md += "\n";
    }
  }

  md +=
      "\n## Dynamic masks (DDL-SLAM run): mean IoU / precision / recall against the ground "
      "truth\n\n";
  if (tables.value("masks", json::array()).empty()) {
    md += "No sequence has ground-truth masks (dynamic_mask/).\n";
  } else {
    md +=
        "| sequence | frames | CNN IoU | P | R | geometry IoU | P | R | free space IoU | P | R | "
        "combined IoU | P | R | moved box recall: CNN | geometry | free space | combined | frames "
        "without dynamic truth | combined FP px on them |\n";
    md += "| --- |";
    for (int i = 0; i < 19; ++i) md += " ---: |";
    md += "\n";
    for (const json& r : tables["masks"]) {
      md += "| " + r.at("sequence").get<std::string>() + " | " +
            count_cell(r["combined"]["frames"]) + " |";
      for (const char* source : kMaskSources) {
        for (const char* metric : {"mean_iou", "precision", "recall"}) {
          md += fmt::format(" {} |", cell(r[source][metric], "{:.3f}"));
        }
      }
      const json& box = r["moved_object"];
      for (const char* source : kMaskSources) {
        md += fmt::format(
            " {} |", box.is_object() ? cell(box["recall"][source], "{:.3f}") : std::string("-"));
      }
      md += fmt::format(" {} | {} |\n", count_cell(r["combined"]["static_frames"]),
                        count_cell(r["combined"]["static_false_positive_px"]));
    }
  }

  md += "\n## Tracking\n\n";
  md +=
      "| sequence | ORB-SLAM2 frames | tracked | ratio | wall s | DDL-SLAM frames | tracked | "
      "ratio | wall s |\n| --- |";
  for (int i = 0; i < 8; ++i) md += " ---: |";
  md += "\n";
  for (const json& r : tables.value("tracking", json::array())) {
    md += "| " + r.at("sequence").get<std::string>() + " |";
    for (const char* column : {"baseline", "ours"}) {
      const json& c = r[column];
      if (!c.is_object()) {
        md += " - | - | - | - |";
        continue;
      }
      md += fmt::format(" {} | {} | {} | {}{}{} |", count_cell(c["frames_processed"]),
                        count_cell(c["frames_tracked"]), cell(c["tracked_ratio"], "{:.3f}"),
                        cell(c["wall_time_s"], "{:.1f}"),
                        c.value("interrupted", false) ? " (interrupted)" : "",
                        c.value("failed", false) ? " (failed)" : "");
    }
    md += "\n";
  }
  const json& skipped = tables.value("skipped", json::array());
  if (!skipped.empty()) {
    md += "\n## Skipped\n\n";
    for (const json& s : skipped) {
      md += "- " + s.value("sequence", std::string("?")) + ": " +
            s.value("reason", std::string("?")) + "\n";
    }
  }
  return md;
}

}  // namespace ddl::eval
