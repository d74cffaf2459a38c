#include "harness/frames.h"

#include <map>
#include <string>
#include <tuple>

namespace ab {

using nlohmann::json;

namespace {

/// One frame of one case: the update and the ray sets' closest-hit medians summed.
struct FrameFigures {
  double update = 0.0;
  double trace = 0.0;
};

/// (scene, config_label, threads): a case of the summary.
using CaseKey = std::tuple<std::string, std::string, int>;

/// The configuration label without its ":strategy" suffix.
std::string base_label(const std::string& label) {
  return label.substr(0, label.rfind(':'));
}

/// Every animated closest-hit row's figures, by case and frame.
std::map<CaseKey, std::map<uint64_t, FrameFigures>> collect(const json& results) {
  std::map<CaseKey, std::map<uint64_t, FrameFigures>> out;
  for (const json& r : results) {
    if (!r.contains("frame") || r.value("query", "") != "closest" || !r.contains("seconds_median")) continue;
    FrameFigures& f = out[{r.value("scene", ""), r.value("config_label", ""), r.value("threads", 0)}]
                         [r["frame"].get<uint64_t>()];
    f.update = r.value("update_seconds", 0.0);
    f.trace += r["seconds_median"].get<double>();
  }
  return out;
}

/// The summary entry of one case.
json case_summary(const CaseKey& key, const std::map<uint64_t, FrameFigures>& frames) {
  json list = json::array();
  double sum = 0.0;
  size_t steady = 0;
  for (const auto& [frame, f] : frames) {
    list.push_back({{"frame", frame},
                    {"update_seconds", f.update},
                    {"trace_seconds", f.trace},
                    {"frame_seconds", f.update + f.trace}});
    if (frame > 0) sum += f.update + f.trace, ++steady;
  }
  const std::string& label = std::get<1>(key);
  return {{"scene", std::get<0>(key)},
          {"config_label", label},
          {"configuration", base_label(label)},
          {"strategy", label.substr(label.rfind(':') + 1)},
          {"threads", std::get<2>(key)},
          {"frames", list},
          {"mean_frame_seconds", steady ? json(sum / double(steady)) : json()}};
}

/// The first frame (after the first) at which refit's frame time exceeds rebuild's.
json refit_stops_paying(const std::map<uint64_t, FrameFigures>& refit,
                        const std::map<uint64_t, FrameFigures>& rebuild) {
  for (const auto& [frame, f] : refit) {
    const auto it = rebuild.find(frame);
    if (frame == 0 || it == rebuild.end()) continue;
    if (f.update + f.trace > it->second.update + it->second.trace) return frame;
  }
  return nullptr;
}

}  // namespace

void fill_frame_summary(json& report) {
  if (!report.contains("results")) return;
  const auto cases = collect(report["results"]);
  if (cases.empty()) return;
  for (json& r : report["results"]) {
    if (!r.contains("frame") || r.value("query", "") != "closest") continue;
    const auto it = cases.find({r.value("scene", ""), r.value("config_label", ""), r.value("threads", 0)});
    if (it == cases.end()) continue;
    const auto f = it->second.find(r["frame"].get<uint64_t>());
    if (f != it->second.end()) r["frame_seconds"] = f->second.update + f->second.trace;
  }
  json summary = json::array();
  for (const auto& [key, frames] : cases) {
    json s = case_summary(key, frames);
    if (s["strategy"] == "refit") {
      const auto rebuild = cases.find(
          {std::get<0>(key), s["configuration"].get<std::string>() + ":rebuild", std::get<2>(key)});
      s["refit_stops_paying_frame"] =
          rebuild == cases.end() ? json() : refit_stops_paying(frames, rebuild->second);
    }
    summary.push_back(s);
  }
  report["frame_summary"] = summary;
}

}  // namespace ab
