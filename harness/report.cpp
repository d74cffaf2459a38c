#include "harness/report.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iomanip>
#include <iostream>
#include <map>
#include <sstream>

#include "datasets/atomic_file.h"
#include "harness/analysis.h"
#include "harness/terminal.h"

namespace ab {

const std::vector<std::string>& csv_columns() {
  static const std::vector<std::string> columns{"scene",
                                                "triangles",
                                                "accelerator",
                                                "config_label",
                                                "params",
                                                "rays",
                                                "ray_kind",
                                                "ray_count",
                                                "query",
                                                "threads",
                                                "threads_used",
                                                "repetitions",
                                                "iterations",
                                                "seconds_median",
                                                "seconds_min",
                                                "seconds_max",
                                                "seconds_mean",
                                                "seconds_stddev",
                                                "rays_per_second",
                                                "rays_per_second_min",
                                                "rays_per_second_max",
                                                "ratio_to_embree",
                                                "cpu_seconds_median",
                                                "rays_per_cpu_second",
                                                "cpu_ratio_to_embree",
                                                "nodes_per_ray",
                                                "leaves_per_ray",
                                                "prims_per_ray",
                                                "mailbox_skips_per_ray",
                                                "havran_cost_per_ray",
                                                "sah_cost",
                                                "epo",
                                                "build_seconds_median",
                                                "build_seconds_min",
                                                "build_seconds_max",
                                                "bytes",
                                                "bytes_per_triangle",
                                                "peak_bytes",
                                                "peak_bytes_per_triangle",
                                                "nodes",
                                                "leaves",
                                                "max_depth",
                                                "references_per_triangle",
                                                "verified",
                                                "brute_rays_checked",
                                                "brute_mismatches",
                                                "reference_rays_checked",
                                                "reference_mismatches",
                                                "thread_mismatches",
                                                "any_hit_mismatches",
                                                "embree_agree",
                                                "embree_tie",
                                                "embree_edge",
                                                "embree_graze",
                                                "embree_limit",
                                                "embree_unexplained",
                                                "frame",
                                                "strategy",
                                                "update_seconds",
                                                "rebuilt",
                                                "update_sah_cost",
                                                "sah_ratio_to_rebuild",
                                                "frame_seconds",
                                                "embree_rounding"};
  return columns;
}

namespace {

std::string csv_cell(const nlohmann::json& v) {
  if (v.is_null()) return "";
  if (v.is_object()) {  // parameters: k=v;k=v
    std::string s;
    for (const auto& [k, x] : v.items())
      s += (s.empty() ? "" : ";") + k + "=" + (x.is_string() ? x.get<std::string>() : x.dump());
    return csv_cell(nlohmann::json(s));
  }
  if (!v.is_string()) return v.dump();
  const std::string s = v.get<std::string>();
  if (s.find_first_of(",\"\n") == std::string::npos) return s;
  std::string q = "\"";
  for (char c : s) q += c == '"' ? std::string("\"\"") : std::string(1, c);
  return q + "\"";
}

}  // namespace

std::string report_csv(const nlohmann::json& report) {
  std::ostringstream out;
  const auto& cols = csv_columns();
  for (size_t i = 0; i < cols.size(); ++i) out << (i ? "," : "") << cols[i];
  out << "\n";
  for (const auto& row : report.value("results", nlohmann::json::array())) {
    for (size_t i = 0; i < cols.size(); ++i)
      out << (i ? "," : "") << csv_cell(row.value(cols[i], nlohmann::json()));
    out << "\n";
  }
  return out.str();
}

void write_report(const nlohmann::json& report, const std::string& dir) {
  const std::filesystem::path d(dir);
  write_file_atomically((d / "report.json").string(),
                        [&](std::ostream& out) { out << report.dump(2) << "\n"; }, false);
  write_file_atomically((d / "report.csv").string(), [&](std::ostream& out) { out << report_csv(report); },
                        false);
}

namespace {

std::string fmt(double v, int precision) {
  if (std::isnan(v)) return "-";
  std::ostringstream s;
  s << std::fixed << std::setprecision(precision) << v;
  return s.str();
}

void print_verification_line(std::ostream& out, const nlohmann::json& report) {
  const auto& v = report.value("verification", nlohmann::json::object());
  uint64_t checks = 0;
  for (const auto& b : report.value("builds", nlohmann::json::array()))
    checks += b.value("verification", nlohmann::json::array()).size();
  if (report.value("scenes", nlohmann::json::array()).empty()) {
    out << "verification: none (no scenes)\n";
    return;
  }
  if (checks == 0) {
    out << "verification: none (no ray sets: builds only)\n";
    return;
  }
  const uint64_t brute_rays = v.value("brute_rays", 0);
  out << "verification: " << checks << " configuration x ray set checks against brute force ("
      << (brute_rays ? "first " + std::to_string(brute_rays) + " rays of each set" : std::string("all rays"))
      << "), " << v.value("reference", "") << " (all rays) and Embree; "
      << report.value("failures", nlohmann::json::array()).size() << " failures\n";
}

void print_correlation_line(std::ostream& out, const nlohmann::json& report) {
  for (const auto& [key, name] : {std::pair{"pearson", "SAH cost"}, std::pair{"epo_pearson", "EPO"}}) {
    std::vector<double> r;
    for (const auto& g : report.value("sah_correlation", nlohmann::json::array()))
      if (g.contains(key) && g[key].is_number()) r.push_back(g[key].get<double>());
    if (r.empty()) continue;
    std::sort(r.begin(), r.end());
    out << name << " vs measured cost per ray (Pearson r over configurations): median "
        << fmt(r[r.size() / 2], 2) << ", min " << fmt(r.front(), 2) << ", max " << fmt(r.back(), 2)
        << " over " << r.size() << " scene x ray set groups\n";
  }
}

}  // namespace

void print_summary_table(std::ostream& out, const nlohmann::json& report, bool color) {
  std::vector<std::string> order;
  const auto by_config = summarize_configs(report, order);
  const int max_threads = report.value("max_threads", 0);
  const Colors c = colors(color);
  out << "geometric means over scenes and ray sets (closest hit); ratio = rays/s / embree's rays/s in this "
         "run; cpu@1 = the same by the process's cpu time\n";
  out << std::left << std::setw(30) << "accelerator" << std::right << std::setw(9) << "ratio@1"
      << std::setw(7) << "cpu@1" << std::setw(9) << ("ratio@" + std::to_string(max_threads)) << std::setw(10)
      << "Mray/s@1" << std::setw(10) << ("Mray/s@" + std::to_string(max_threads)) << std::setw(11)
      << "build Mt/s" << std::setw(8) << "B/tri" << std::setw(10) << "nodes/ray" << std::setw(10)
      << "tris/ray"
      << "  verified\n";
  for (const auto& label : order) {
    const ConfigSummary& s = by_config.at(label);
    out << std::left << std::setw(30) << label.substr(0, 29) << std::right << std::setw(9)
        << fmt(s.ratio_one.value(), 2) << std::setw(7) << fmt(s.cpu_ratio_one.value(), 2) << std::setw(9)
        << fmt(s.ratio_all.value(), 2) << std::setw(10) << fmt(s.mrays_one.value(), 2) << std::setw(10)
        << fmt(s.mrays_all.value(), 2) << std::setw(11) << fmt(s.build_rate.value(), 2) << std::setw(8)
        << fmt(s.bytes.value(), 1) << std::setw(10) << fmt(s.nodes.value(), 1) << std::setw(10)
        << fmt(s.prims.value(), 1) << "  " << (s.verified ? c.green : c.red) << (s.verified ? "ok" : "FAILED")
        << c.reset << "\n";
  }
  print_verification_line(out, report);
  print_correlation_line(out, report);
}

}  // namespace ab
