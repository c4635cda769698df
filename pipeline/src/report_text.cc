// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
// What a person reads: the metrics table (terminal and index.html) and the HTML page.
#include <cstdio>
#include <sstream>

#include "stages.h"

namespace gcpstereo::pipeline::internal {
namespace {

using nlohmann::json;

std::string Percent(const json& v) {
  if (!v.is_number()) return "n/a";
  char buffer[32];
  std::snprintf(buffer, sizeof(buffer), "%.2f %%", v.get<double>());
  return buffer;
}

std::string Number(const json& v, const char* format = "%.4g") {
  if (!v.is_number()) return "n/a";
  char buffer[32];
  std::snprintf(buffer, sizeof(buffer), format, v.get<double>());
  return buffer;
}

using Table = std::vector<std::vector<std::string>>;

// One table per kind of ground truth, the first row its header.
std::vector<std::pair<std::string, Table>> MetricsTables(const json& metrics) {
  std::vector<std::pair<std::string, Table>> tables;
  if (metrics.contains("depth_sigma")) {
    Table t{{"depth map", "within 1σ", "within 2σ", "within 3σ", "within 10σ", "missing",
             "mean |error|"}};
    for (const auto& [name, h] : metrics["depth_sigma"].items()) {
      const json& w = h["within_n_sigma_percent"];
      t.push_back({name, Percent(w[0]), Percent(w[1]), Percent(w[2]), Percent(w[9]),
                   Percent(h["missing_percent"]), Number(h["mean_abs_error"])});
    }
    tables.emplace_back("Depth error in units of the laser's sigma (Strecha et al.)", t);
  }
  if (metrics.contains("middlebury")) {
    Table t{{"disparity map", "nonocc bad-1", "all bad-1", "disc bad-1", "nonocc bad-0.5",
             "nonocc bad-2", "all mean |error| px"}};
    for (const auto& item : metrics["middlebury"].items()) {
      // Not a structured binding: C++17 does not let a lambda capture one (clang refuses it).
      const std::string& name = item.key();
      const json& r = item.value();
      if (!r.is_object()) continue;
      auto bad = [&](const char* region, int index) {
        const json& stats = r[region];
        return stats["available"].get<bool>() ? Percent(stats["bad_percent"][index]) : "n/a";
      };
      t.push_back({name, bad("nonocc", 1), bad("all", 1), bad("disc", 1), bad("nonocc", 0),
                   bad("nonocc", 2), Number(r["all"]["mean_abs_error_px"], "%.3f")});
    }
    tables.emplace_back("Middlebury bad-pixel rates (|d − d_gt| > t px; masks: " +
                            metrics["middlebury"].value("masks", std::string("?")) + ")",
                        t);
  }
  if (metrics.contains("lidar_holdout")) {
    Table t{{"map", "bad-3 (>3 px and >5 %)", "bad-1", "mean |error|", "points"}};
    for (const auto& [name, s] : metrics["lidar_holdout"].items()) {
      if (!s.is_object()) continue;
      t.push_back({name, Percent(s["bad3_percent"]), Percent(s["bad1_percent"]),
                   Number(s["mean_abs_error"], "%.3f"), std::to_string(s["counted"].get<long>())});
    }
    tables.emplace_back(
        "Held-out LiDAR points (" + metrics["lidar_holdout"].value("unit", std::string()) + ")", t);
  }
  if (metrics.contains("sfm_holdout")) {
    Table t{{"map", "> 1 %", "> 2 %", "> 5 %", "median", "points (missing)"}};
    for (const auto& [name, s] : metrics["sfm_holdout"].items()) {
      if (!s.is_object()) continue;
      t.push_back({name, Percent(s["above_1_percent"]), Percent(s["above_2_percent"]),
                   Percent(s["above_5_percent"]), Percent(s["median_relative_error_percent"]),
                   std::to_string(s["counted"].get<long>()) + " (" +
                       std::to_string(s["missing"].get<long>()) + ")"});
    }
    tables.emplace_back("Held-out SfM points (relative depth error)", t);
  }
  return tables;
}

std::string Escape(const std::string& s) {
  std::string out;
  for (char c : s) {
    switch (c) {
      case '<':
        out += "&lt;";
        break;
      case '>':
        out += "&gt;";
        break;
      case '&':
        out += "&amp;";
        break;
      default:
        out += c;
    }
  }
  return out;
}

}  // namespace

std::string TerminalSummary(const json& report) {
  std::ostringstream s;
  if (report.contains("gcps")) {
    s << "GCPs: " << report["gcps"]["count"] << " ("
      << Number(report["gcps"]["density_percent"], "%.2f") << " % of the pixels)\n";
  }
  if (report.contains("metrics")) {
    for (const auto& [title, table] : MetricsTables(report["metrics"])) {
      s << title << "\n";
      std::vector<size_t> widths(table.front().size(), 0);
      for (const auto& row : table) {
        for (size_t i = 0; i < row.size(); ++i) widths[i] = std::max(widths[i], row[i].size());
      }
      for (const auto& row : table) {
        s << " ";
        for (size_t i = 0; i < row.size(); ++i) {
          s << " " << row[i] << std::string(widths[i] - row[i].size() + 1, ' ');
        }
        s << "\n";
      }
    }
  }
  return s.str();
}

std::string MakeIndexHtml(const json& report, const std::vector<std::string>& images) {
  std::ostringstream h;
  h << "<!DOCTYPE html>\n<html><head><meta charset=\"utf-8\"><title>gcpstereo run</title>\n"
    << "<style>body{font-family:sans-serif;margin:2em;background:#fafafa}"
       "table{border-collapse:collapse;margin:1em 0}td,th{border:1px solid #bbb;padding:4px 10px;"
       "text-align:right}th{background:#eee}td:first-child{text-align:left}"
       "figure{display:inline-block;margin:0.5em;vertical-align:top}"
       "img{max-width:720px;border:1px solid #ccc}</style></head><body>\n";
  h << "<h1>gcpstereo run</h1>\n<p>Configuration: <code>" << Escape(report.value("config", ""))
    << "</code>; data set <code>" << Escape(report["dataset"].value("path", ""))
    << "</code>, reference <b>" << Escape(report["dataset"]["reference"].value("name", ""))
    << "</b> (" << report["dataset"]["reference"].value("width", 0) << "×"
    << report["dataset"]["reference"].value("height", 0) << "), "
    << report["dataset"].value("num_views", 0) << " views.</p>\n";
  if (report.contains("metrics")) {
    for (const auto& [title, table] : MetricsTables(report["metrics"])) {
      h << "<h2>" << Escape(title) << "</h2>\n<table>\n";
      for (size_t r = 0; r < table.size(); ++r) {
        h << "<tr>";
        for (const auto& cell : table[r]) {
          h << (r == 0 ? "<th>" : "<td>") << Escape(cell) << (r == 0 ? "</th>" : "</td>");
        }
        h << "</tr>\n";
      }
      h << "</table>\n";
    }
  }
  if (report.contains("stages")) {
    h << "<h2>Stages</h2>\n<table><tr><th>stage</th><th>seconds</th><th>peak memory after "
         "(MB)</th></tr>\n";
    for (const auto& [name, stage] : report["stages"].items()) {
      h << "<tr><td>" << Escape(name) << "</td><td>" << Number(stage["seconds"], "%.2f")
        << "</td><td>" << Number(json(stage["peak_memory_bytes_after"].get<double>() / 1e6), "%.0f")
        << "</td></tr>\n";
    }
    h << "</table>\n";
  }
  h << "<h2>Pictures</h2>\n";
  for (const auto& image : images) {
    h << "<figure><img src=\"" << Escape(image) << "\" alt=\"" << Escape(image) << "\"><figcaption>"
      << Escape(image) << "</figcaption></figure>\n";
  }
  h << "<p>Everything measured is in <a href=\"report.json\">report.json</a>; the configuration "
       "used in <a href=\"effective_config.yaml\">effective_config.yaml</a>.</p>\n</body></html>\n";
  return h.str();
}

}  // namespace gcpstereo::pipeline::internal
