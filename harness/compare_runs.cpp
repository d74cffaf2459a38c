#include "harness/compare_runs.h"

#include <cmath>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <map>
#include <sstream>

#include "accel/core/error.h"
#include "harness/mann_whitney.h"

namespace ab {

using nlohmann::json;

json load_run_report(const std::string& path) {
  std::filesystem::path file(path);
  if (std::filesystem::is_directory(file)) file /= "report.json";
  std::ifstream in(file);
  if (!in) throw InputError(file.string() + ": cannot open (give a run folder or its report.json)");
  json j;
  try {
    in >> j;
  } catch (const json::exception& e) {
    throw InputError(file.string() + ": not valid JSON (" + std::string(e.what()) + ")");
  }
  if (!j.is_object() || !j.contains("results") || !j["results"].is_array())
    throw InputError(file.string() + ": not an accelbench report (no \"results\" array)");
  return j;
}

bool RunComparison::regressed() const {
  for (const CaseComparison& c : cases)
    if (c.change == Change::kRegression) return true;
  return false;
}

std::string change_name(Change c) {
  switch (c) {
    case Change::kImprovement:
      return "improvement";
    case Change::kRegression:
      return "REGRESSION";
    case Change::kUntested:
      return "untested";
    default:
      return "unchanged";
  }
}

namespace {

/// One case of one run: its description, median seconds and every repetition's seconds.
struct Sample {
  CaseComparison id;  ///< scene, config, rays, query, threads
  double median = 0.0;
  std::vector<double> seconds;
};

std::string case_key(const CaseComparison& c) {
  return c.scene + " / " + c.config + (c.rays.empty() ? "" : " / " + c.rays) + " / " + c.query +
         (c.threads >= 0 ? " / threads " + std::to_string(c.threads) : "");
}

std::vector<double> numbers(const json& j) {
  std::vector<double> out;
  if (j.is_array())
    for (const json& x : j)
      if (x.is_number()) out.push_back(x.get<double>());
  return out;
}

/// The timed cases of a report, in its order: every query row, then every build.
/// The scene of a row or build entry, with " frame N" for a frame of an animated scene (part of the case).
std::string scene_of(const json& r) {
  const std::string scene = r.value("scene", "");
  return r.contains("frame") ? scene + " frame " + r["frame"].dump() : scene;
}

std::vector<std::pair<std::string, Sample>> cases_of(const json& report, bool cpu) {
  std::vector<std::pair<std::string, Sample>> out;
  for (const json& r : report["results"]) {
    const std::string query = r.value("query", "");
    if (query == "build" || !r.contains("seconds_median")) continue;
    Sample s;
    s.id.scene = scene_of(r);
    s.id.config = r.value("config_label", r.value("accelerator", ""));
    s.id.rays = r.value("rays", "");
    s.id.query = query;
    s.id.threads = r.value("threads", 0);
    s.median = r.value(cpu ? "cpu_seconds_median" : "seconds_median", 0.0);
    s.seconds = numbers(r.value(cpu ? "cpu_seconds_samples" : "seconds_samples", json()));
    out.emplace_back(case_key(s.id), s);
  }
  for (const json& b : report.value("builds", json::array())) {
    if (!b.contains("build_seconds")) continue;
    Sample s;
    s.id.scene = scene_of(b);
    s.id.config = b.value("config_label", b.value("accelerator", ""));
    s.id.query = "build";
    s.id.threads = -1;
    s.median = b["build_seconds"].value("median", 0.0);
    s.seconds = numbers(b["build_seconds"].value("samples", json()));
    out.emplace_back(case_key(s.id), s);
  }
  return out;
}

/// The verdict on one case: the ratio (rays/s NEW/BASE for a query, seconds NEW/BASE for a build), the test
/// over the repetitions, and whether the change is beyond the threshold and significant.
CaseComparison compare_case(const Sample& base, const Sample& next, double threshold, double alpha) {
  CaseComparison c = base.id;
  c.base_median = base.median;
  c.new_median = next.median;
  const bool build = c.query == "build";
  if (base.median > 0 && next.median > 0)
    c.ratio = build ? next.median / base.median : base.median / next.median;
  c.base_repetitions = base.seconds.size();
  c.new_repetitions = next.seconds.size();
  c.p_value = std::nan("");
  if (!base.seconds.empty() && !next.seconds.empty()) {
    const MannWhitney t = mann_whitney_u(base.seconds, next.seconds);
    c.p_value = t.p_value;
    c.exact = t.exact;
  }
  const bool slower = build ? c.ratio > 1.0 + threshold : c.ratio < 1.0 - threshold;
  const bool faster = build ? c.ratio < 1.0 - threshold : c.ratio > 1.0 + threshold;
  if (!slower && !faster) return c;
  if (std::isnan(c.p_value))
    c.change = Change::kUntested;
  else if (c.p_value < alpha)
    c.change = slower ? Change::kRegression : Change::kImprovement;
  return c;
}

/// A warning when the field differs between the runs.
void warn_if_different(const json& base, const json& next, const std::string& section,
                       const std::vector<std::string>& fields, const std::string& what,
                       std::vector<std::string>& warnings) {
  const json a = base.value(section, json::object()), b = next.value(section, json::object());
  for (const std::string& f : fields) {
    const json x = a.is_object() ? a.value(f, json()) : json(),
               y = b.is_object() ? b.value(f, json()) : json();
    if (x != y) {
      warnings.push_back("the runs come from different " + what + " (" + section + "." + f + ": " + x.dump() +
                         " vs " + y.dump() + ")");
      return;
    }
  }
}

}  // namespace

RunComparison compare_runs(const json& base, const json& next, double threshold, double alpha, bool cpu) {
  RunComparison out;
  out.threshold = threshold;
  out.alpha = alpha;
  out.cpu = cpu;
  warn_if_different(base, next, "machine",
                    {"cpu_model", "logical_cores", "tbb_default_concurrency", "hostname"}, "machines",
                    out.warnings);
  warn_if_different(base, next, "compiler", {"compiler", "version", "flags"}, "compilers", out.warnings);
  if (base.value("suite_name", json()) != next.value("suite_name", json()) ||
      base.value("suite", json()) != next.value("suite", json()))
    out.warnings.push_back("the runs come from different suites (" + base.value("suite_name", json()).dump() +
                           " vs " + next.value("suite_name", json()).dump() + ")");
  const auto base_cases = cases_of(base, cpu), next_cases = cases_of(next, cpu);
  for (const auto* cases : {&base_cases, &next_cases})
    for (const auto& [key, s] : *cases)
      if (cpu && s.id.query != "build" && s.median <= 0) {
        out.warnings.push_back(std::string(cases == &base_cases ? "BASE" : "NEW") +
                               " has no cpu times (a report from before they were kept): " + key);
        break;
      }
  std::map<std::string, const Sample*> in_next, in_base;
  for (const auto& [key, s] : next_cases) in_next.emplace(key, &s);
  for (const auto& [key, s] : base_cases) in_base.emplace(key, &s);
  for (const auto& [key, s] : base_cases) {
    const auto it = in_next.find(key);
    if (it == in_next.end())
      out.only_base.push_back(key);
    else
      out.cases.push_back(compare_case(s, *it->second, threshold, alpha));
  }
  for (const auto& [key, s] : next_cases)
    if (!in_base.count(key)) out.only_new.push_back(key);
  return out;
}

namespace {

json number_or_null(double x) {
  return std::isfinite(x) ? json(x) : json();
}

}  // namespace

json to_json(const RunComparison& c) {
  json cases = json::array();
  for (const CaseComparison& x : c.cases)
    cases.push_back({{"scene", x.scene},
                     {"config_label", x.config},
                     {"rays", x.rays},
                     {"query", x.query},
                     {"threads", x.threads >= 0 ? json(x.threads) : json()},
                     {"base_seconds_median", x.base_median},
                     {"new_seconds_median", x.new_median},
                     {"ratio", x.ratio},
                     {"ratio_of", x.query == "build" ? "build seconds" : "rays per second"},
                     {"p_value", number_or_null(x.p_value)},
                     {"exact", x.exact},
                     {"base_repetitions", x.base_repetitions},
                     {"new_repetitions", x.new_repetitions},
                     {"change", change_name(x.change)}});
  return {{"threshold", c.threshold},    {"alpha", c.alpha},         {"cpu", c.cpu},
          {"regressed", c.regressed()},  {"warnings", c.warnings},   {"cases", cases},
          {"only_in_base", c.only_base}, {"only_in_new", c.only_new}};
}

namespace {

std::string csv_field(const std::string& s) {
  if (s.find_first_of(",\"\n") == std::string::npos) return s;
  std::string q = "\"";
  for (char ch : s) q += ch == '"' ? std::string("\"\"") : std::string(1, ch);
  return q + "\"";
}

}  // namespace

std::string to_csv(const RunComparison& c) {
  std::ostringstream out;
  out << "scene,config_label,rays,query,threads,base_seconds_median,new_seconds_median,ratio,p_value,exact,"
         "base_repetitions,new_repetitions,change\n";
  out << std::setprecision(9);
  for (const CaseComparison& x : c.cases) {
    out << csv_field(x.scene) << "," << csv_field(x.config) << "," << csv_field(x.rays) << "," << x.query
        << "," << (x.threads >= 0 ? std::to_string(x.threads) : "") << "," << x.base_median << ","
        << x.new_median << "," << x.ratio << "," << (std::isnan(x.p_value) ? "" : std::to_string(x.p_value))
        << "," << (x.exact ? "true" : "false") << "," << x.base_repetitions << "," << x.new_repetitions << ","
        << change_name(x.change) << "\n";
  }
  return out.str();
}

void print_comparison(std::ostream& out, const RunComparison& c) {
  for (const std::string& w : c.warnings) out << "warning: " << w << "\n";
  out << "ratio = NEW/BASE of the medians (rays/s for queries" << (c.cpu ? " by cpu time" : "")
      << ", seconds for builds); change beyond " << c.threshold * 100 << "% and Mann-Whitney p < " << c.alpha
      << "\n";
  out << std::left << std::setw(64) << "case" << std::right << std::setw(12) << "base ms" << std::setw(12)
      << "new ms" << std::setw(8) << "ratio" << std::setw(9) << "p"
      << "  change\n";
  for (const CaseComparison& x : c.cases) {
    std::ostringstream p;
    if (std::isnan(x.p_value))
      p << "-";
    else
      p << std::setprecision(2) << x.p_value;
    out << std::left << std::setw(64) << case_key(x).substr(0, 63) << std::right << std::fixed
        << std::setprecision(3) << std::setw(12) << x.base_median * 1e3 << std::setw(12) << x.new_median * 1e3
        << std::setw(8) << x.ratio << std::defaultfloat << std::setw(9) << p.str() << "  "
        << change_name(x.change) << "\n";
  }
  for (const std::string& k : c.only_base) out << "only in BASE: " << k << "\n";
  for (const std::string& k : c.only_new) out << "only in NEW: " << k << "\n";
  size_t regressions = 0, improvements = 0;
  for (const CaseComparison& x : c.cases) {
    regressions += x.change == Change::kRegression;
    improvements += x.change == Change::kImprovement;
  }
  out << c.cases.size() << " cases compared: " << regressions << " significant regressions, " << improvements
      << " significant improvements\n";
}

}  // namespace ab
