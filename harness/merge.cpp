#include "harness/merge.h"

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>

#include "accel/core/error.h"
#include "datasets/atomic_file.h"
#include "harness/frames.h"
#include "harness/report.h"

namespace ab {

namespace {

using nlohmann::json;
namespace fs = std::filesystem;

/// One shard folder as read.
struct ShardRun {
  std::string dir;  ///< the folder as given
  json report;      ///< its report.json
  json gbench;      ///< its gbench.json
  int index = 0;    ///< shard.index
  int count = 0;    ///< shard.count
  std::string name() const { return std::to_string(index) + "/" + std::to_string(count); }
};

json read_json(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw InputError(path + ": cannot open (not a folder written by accelbench run --shard?)");
  try {
    return json::parse(in);
  } catch (const json::parse_error& e) {
    const std::string what = e.what();
    const auto colon = what.find("] ");
    throw InputError(path +
                     ": invalid JSON: " + (colon == std::string::npos ? what : what.substr(colon + 2)));
  }
}

/// Reads a shard folder and checks that it holds a finished shard.
ShardRun read_shard(const std::string& dir) {
  ShardRun s;
  s.dir = dir;
  const std::string path = (fs::path(dir) / "report.json").string();
  s.report = read_json(path);
  if (!s.report.is_object() || !s.report.contains("results") || !s.report.contains("suite_hash"))
    throw InputError(path + ": not a report of accelbench run (no 'results' or 'suite_hash')");
  if (!s.report.contains("shard"))
    throw InputError(path + ": not a shard (no 'shard'; run the suite with --shard K/N)");
  s.index = s.report["shard"].at("index").get<int>();
  s.count = s.report["shard"].at("count").get<int>();
  if (s.report.value("interrupted", true) || !s.report.value("complete", false))
    throw InputError(dir + ": shard " + s.name() +
                     " was interrupted (its report is incomplete; run it again)");
  s.gbench = read_json((fs::path(dir) / "gbench.json").string());
  return s;
}

/// The value at a JSON pointer as text, for the messages.
std::string at(const json& report, const char* pointer) {
  const json& v = report.value(json::json_pointer(pointer), json());
  return v.is_string() ? v.get<std::string>() : v.dump();
}

/// Shards of one suite, commit, schema and shard count, computing the same partition.
void check_same_run(const ShardRun& first, const ShardRun& s) {
  auto differs = [&](const char* pointer, const std::string& what) {
    if (at(first.report, pointer) != at(s.report, pointer))
      throw InputError(s.dir + ": " + what + " " + at(s.report, pointer) + " differs from " + first.dir +
                       "'s " + at(first.report, pointer));
  };
  differs("/schema_version", "report schema");
  differs("/suite_hash", "suite (hash)");
  differs("/source/git_commit", "commit");
  differs("/shard/count", "shard count");
  if (first.report["shard"]["partition"] != s.report["shard"]["partition"])
    throw InputError(s.dir + ": shard " + s.name() + " partitioned the suite differently from " + first.dir +
                     " (did its mesh or scene files change?)");
}

/// Every shard 1..N exactly once; returns them in index order.
std::vector<ShardRun> order_shards(std::vector<ShardRun> shards) {
  const int n = shards.front().count;
  std::vector<const ShardRun*> by_index(size_t(n) + 1, nullptr);
  for (const ShardRun& s : shards) {
    if (s.index < 1 || s.index > n)
      throw InputError(s.dir + ": shard index " + s.name() + " is out of range");
    if (by_index[size_t(s.index)])
      throw InputError(s.dir + ": shard " + s.name() + " given twice (also " +
                       by_index[size_t(s.index)]->dir + ")");
    by_index[size_t(s.index)] = &s;
  }
  for (int k = 1; k <= n; ++k)
    if (!by_index[size_t(k)])
      throw InputError("merge: shard " + std::to_string(k) + "/" + std::to_string(n) + " is missing (" +
                       std::to_string(shards.size()) + " of " + std::to_string(n) + " shard folders given)");
  std::sort(shards.begin(), shards.end(),
            [](const ShardRun& a, const ShardRun& b) { return a.index < b.index; });
  return shards;
}

/// The shard's report holds exactly the scenes of its part (a crashed shard lacks some).
void check_scenes(const ShardRun& s) {
  std::set<std::string> own;
  for (const json& label : s.report["shard"].at("scenes")) own.insert(label.get<std::string>());
  std::set<std::string> reported;
  for (const json& scene : s.report.at("scenes")) reported.insert(scene.at("label").get<std::string>());
  for (const std::string& label : own)
    if (!reported.count(label))
      throw InputError(s.dir + ": shard " + s.name() + " has no entry for its scene '" + label + "'");
  for (const char* list : {"scenes", "builds", "results"})
    for (const json& item : s.report.at(list)) {
      const std::string scene = item.contains("label") ? item["label"] : item.at("scene");
      if (!own.count(scene))
        throw InputError(s.dir + ": shard " + s.name() + " has " + list + " of scene '" + scene +
                         "', which is not in its part");
    }
}

/// The items of `list` of every shard, in the suite's scene order (each scene belongs to one shard).
json in_scene_order(const std::vector<ShardRun>& shards, const char* list, const char* scene_key) {
  std::map<std::string, json> by_scene;
  for (const ShardRun& s : shards)
    for (const json& item : s.report.at(list))
      by_scene[item.at(scene_key).get<std::string>()].push_back(item);
  json out = json::array();
  for (const json& label : shards.front().report["shard"].at("suite_scenes"))
    for (const json& item : by_scene[label.get<std::string>()]) out.push_back(item);
  return out;
}

/// No case (scene, configuration, ray set, query, threads, and frame for animated scenes) twice in the merged
/// results.
void check_unique_cases(const json& results) {
  std::set<std::string> seen;
  for (const json& r : results) {
    const std::string key = at(r, "/scene") + " / " + at(r, "/config_label") + " / " + at(r, "/rays") +
                            " / " + at(r, "/query") + " / threads " + at(r, "/threads") +
                            (r.contains("frame") ? " / frame " + at(r, "/frame") : "");
    if (!seen.insert(key).second) throw InputError("merge: case '" + key + "' appears twice");
  }
}

/// Each shard's machine, compiler, source, libraries and date.
json machines(const std::vector<ShardRun>& shards) {
  json out = json::array();
  for (const ShardRun& s : shards)
    out.push_back({{"shard", s.index},
                   {"dir", s.dir},
                   {"date", s.report.value("date", json())},
                   {"machine", s.report.value("machine", json())},
                   {"compiler", s.report.value("compiler", json())},
                   {"source", s.report.value("source", json())},
                   {"libraries", s.report.value("libraries", json())},
                   {"max_threads", s.report.value("max_threads", json())}});
  return out;
}

json merged_report(const std::vector<ShardRun>& shards) {
  json out = shards.front().report;
  out.erase("shard");
  out["merged"] = {{"shards", shards.size()}, {"partition", shards.front().report["shard"]["partition"]}};
  out["machines"] = machines(shards);
  out["failures"] = json::array();
  out["sah_correlation"] = json::array();
  for (const ShardRun& s : shards) {
    if (!s.report.value("verified", false)) out["verified"] = false;
    for (const json& f : s.report.at("failures")) out["failures"].push_back(f);
    for (const json& g : s.report.at("sah_correlation")) out["sah_correlation"].push_back(g);
    out["date"] = std::min(out.value("date", std::string()), s.report.value("date", std::string()));
  }
  auto& corr = out["sah_correlation"];  // as one run orders them: by scene, then ray set
  std::stable_sort(corr.begin(), corr.end(), [](const json& a, const json& b) {
    return std::make_pair(at(a, "/scene"), at(a, "/rays")) < std::make_pair(at(b, "/scene"), at(b, "/rays"));
  });
  out["scenes"] = in_scene_order(shards, "scenes", "label");
  out["builds"] = in_scene_order(shards, "builds", "scene");
  out["results"] = in_scene_order(shards, "results", "scene");
  fill_frame_summary(out);  // over every shard's animated scenes, as one run sums them
  out["interrupted"] = false;
  out["complete"] = true;
  return out;
}

json merged_gbench(const std::vector<ShardRun>& shards) {
  json out = {{"context", shards.front().gbench.value("context", json::object())},
              {"benchmarks", json::array()}};
  out["context"]["accelbench_shards"] = shards.size();
  for (const ShardRun& s : shards)
    for (const json& b : s.gbench.value("benchmarks", json::array())) out["benchmarks"].push_back(b);
  return out;
}

std::vector<std::string> merge_notes(const std::vector<ShardRun>& shards) {
  std::set<std::string> cpus;
  for (const ShardRun& s : shards) cpus.insert(at(s.report, "/machine/cpu_model"));
  std::vector<std::string> notes;
  if (cpus.size() > 1)
    notes.push_back(
        "merge: note: the shards ran on " + std::to_string(cpus.size()) +
        " different CPU models (see 'machines'); ratios to Embree are per scene, but compare rays/s "
        "across scenes with care");
  return notes;
}

}  // namespace

MergedRun merge_shards(const std::vector<std::string>& dirs) {
  if (dirs.empty()) throw InputError("merge: no shard folders given");
  std::vector<ShardRun> shards;
  std::string current;  // the folder being checked, for the message on a malformed report
  try {
    for (const std::string& d : dirs) shards.push_back(read_shard(current = d));
    for (const ShardRun& s : shards) {
      current = s.dir;
      check_same_run(shards.front(), s);
    }
    shards = order_shards(std::move(shards));
    for (const ShardRun& s : shards) {
      current = s.dir;
      check_scenes(s);
    }
  } catch (const json::exception& e) {
    throw InputError(current + ": malformed shard report: " + e.what());
  }
  MergedRun run;
  run.report = merged_report(shards);
  check_unique_cases(run.report["results"]);
  run.gbench = merged_gbench(shards);
  run.notes = merge_notes(shards);
  return run;
}

void write_merged(const MergedRun& run, const std::string& dir) {
  write_report(run.report, dir);
  write_file_atomically((fs::path(dir) / "gbench.json").string(),
                        [&](std::ostream& out) { out << run.gbench.dump(2) << "\n"; }, false);
}

}  // namespace ab
