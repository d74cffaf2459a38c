#include "harness/analysis.h"

#include <cmath>
#include <utility>

#include "accel/reference/embree_device.h"

namespace ab {

using nlohmann::json;

double pearson(const std::vector<double>& x, const std::vector<double>& y) {
  const size_t n = std::min(x.size(), y.size());
  if (n < 2) return std::nan("");
  double mx = 0, my = 0;
  for (size_t i = 0; i < n; ++i) mx += x[i], my += y[i];
  mx /= double(n);
  my /= double(n);
  double sxy = 0, sxx = 0, syy = 0;
  for (size_t i = 0; i < n; ++i) {
    sxy += (x[i] - mx) * (y[i] - my);
    sxx += (x[i] - mx) * (x[i] - mx);
    syy += (y[i] - my) * (y[i] - my);
  }
  return sxx > 0 && syy > 0 ? sxy / std::sqrt(sxx * syy) : std::nan("");
}

namespace {

/// Sets `ratio_field` of every row to its `rate_field` over Embree's in the same scene, ray set, query,
/// thread count and frame.
void fill_ratio(json& report, const char* rate_field, const char* ratio_field) {
  std::map<std::string, double> embree;
  auto key = [](const json& r) {
    return r.value("scene", "") + "\n" + r.value("rays", "") + "\n" + r.value("query", "") + "\n" +
           std::to_string(r.value("threads", -1)) + "\n" + r.value("frame", json()).dump();
  };
  for (const json& r : report["results"])
    if (r.value("accelerator", "") == kEmbreeName && r.contains(rate_field) && !embree.count(key(r)))
      embree[key(r)] = r[rate_field].get<double>();
  for (json& r : report["results"]) {
    const auto it = embree.find(key(r));
    if (r.contains(rate_field) && it != embree.end() && it->second > 0)
      r[ratio_field] = r[rate_field].get<double>() / it->second;
  }
}

}  // namespace

void fill_ratios(json& report) {
  fill_ratio(report, "rays_per_second", "ratio_to_embree");
  fill_ratio(report, "rays_per_cpu_second", "cpu_ratio_to_embree");
}

namespace {

/// Pearson's r of `metric` against havran_cost_per_ray over the points that have the metric (null when
/// fewer than three do or r is undefined), with how many points it used.
std::pair<json, size_t> metric_correlation(const json& points, const char* metric) {
  std::vector<double> x, y;
  for (const json& p : points)
    if (p[metric].is_number()) x.push_back(p[metric]), y.push_back(p["havran_cost_per_ray"]);
  const double r = x.size() >= 3 ? pearson(x, y) : std::nan("");
  return {std::isnan(r) ? json() : json(r), x.size()};
}

}  // namespace

// Havran 2000 ("Heuristic Ray Shooting Algorithms", PhD thesis, ch. 2) judges structures by
// hardware-independent counts: traversal steps and intersection tests per ray, combined with the same
// costs the surface area heuristic (Goldsmith and Salmon 1987; MacDonald and Booth 1990) predicts with.
// Aila, Karras and Laine 2013 show the SAH explains that cost only in part and add the end-point overlap
// (EPO, accel/common/epo.h): both metrics are correlated with it, each over the configurations that
// report it. The correlation is Pearson's product-moment coefficient.
void fill_correlations(json& report, int threads) {
  std::map<std::pair<std::string, std::string>, json> groups;
  for (const json& r : report["results"]) {
    if (r.value("query", "") != "closest" || r.value("threads", -1) != threads) continue;
    if (!r["sah_cost"].is_number() || !r.contains("havran_cost_per_ray")) continue;
    json& g = groups[{r["scene"], r["rays"]}];
    g["points"].push_back({{"config_label", r["config_label"]},
                           {"sah_cost", r["sah_cost"]},
                           {"epo", r.value("epo", json())},
                           {"havran_cost_per_ray", r["havran_cost_per_ray"]}});
  }
  report["sah_correlation"] = json::array();
  for (auto& [k, g] : groups) {
    const auto [sah_r, sah_n] = metric_correlation(g["points"], "sah_cost");
    const auto [epo_r, epo_n] = metric_correlation(g["points"], "epo");
    report["sah_correlation"].push_back({{"scene", k.first},
                                         {"rays", k.second},
                                         {"configurations", sah_n},
                                         {"pearson", sah_r},
                                         {"epo_configurations", epo_n},
                                         {"epo_pearson", epo_r},
                                         {"points", g["points"]}});
  }
}

void GeoMean::add(const json& v) {
  if (v.is_number() && v.get<double>() > 0) {
    log_sum += std::log(v.get<double>());
    ++n;
  }
}

double GeoMean::value() const {
  return n ? std::exp(log_sum / n) : std::nan("");
}

namespace {

/// Adds one result row to its configuration's summary.
void add_row(ConfigSummary& s, const json& row, int max_threads) {
  ++s.rows;
  if (!row.value("verified", true)) s.verified = false;
  s.bytes.add(row.value("bytes_per_triangle", json()));
  const double build = row.value("build_seconds_median", 0.0);
  if (build > 0) s.build_rate.add(row.value("triangles", 0.0) / build / 1e6);
  if (row.value("query", "") != "closest") return;
  const bool one = row.value("threads_used", 0) == 1;
  const bool all = row.value("threads_used", 0) == max_threads;
  const double mrays = row.value("rays_per_second", 0.0) / 1e6;
  const json ratio = row.value("ratio_to_embree", json());
  if (all) s.ratio_all.add(ratio), s.mrays_all.add(mrays);
  if (!one) return;
  s.ratio_one.add(ratio);
  s.mrays_one.add(mrays);
  s.cpu_ratio_one.add(row.value("cpu_ratio_to_embree", json()));
  s.nodes.add(row.value("nodes_per_ray", json()));
  s.prims.add(row.value("prims_per_ray", json()));
}

}  // namespace

std::map<std::string, ConfigSummary> summarize_configs(const json& report, std::vector<std::string>& order) {
  std::map<std::string, ConfigSummary> by_config;
  const int max_threads = report.value("max_threads", 0);
  for (const auto& row : report.value("results", json::array())) {
    const std::string label = row.value("config_label", "");
    if (!by_config.count(label)) order.push_back(label);
    add_row(by_config[label], row, max_threads);
  }
  return by_config;
}

}  // namespace ab
