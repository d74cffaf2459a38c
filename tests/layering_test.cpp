// The house's layering, checked on the sources: every #include "..." of the project runs one way
// (accel/core <- accel/common <- the families <- tracer <- harness, datasets beside the tracer and using
// accel/core only), no family includes another, and no files include each other in a loop.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <regex>
#include <set>
#include <string>
#include <vector>

namespace {

namespace fs = std::filesystem;

/// The project's own includes of every source file, by path relative to the source root.
std::map<std::string, std::vector<std::string>> include_graph() {
  const fs::path root = ACCELBENCH_SOURCE_DIR;
  const std::regex include_line(R"(^\s*#\s*include\s+"([^"]+)\")");
  std::map<std::string, std::vector<std::string>> graph;
  for (const char* top : {"accel", "datasets", "tracer", "harness"}) {
    for (const auto& entry : fs::recursive_directory_iterator(root / top)) {
      const std::string ext = entry.path().extension().string();
      if (ext != ".h" && ext != ".cpp") continue;
      const std::string file = fs::relative(entry.path(), root).generic_string();
      std::ifstream in(entry.path());
      std::string line;
      std::smatch m;
      auto& includes = graph[file];
      while (std::getline(in, line))
        if (std::regex_search(line, m, include_line) && fs::exists(root / m[1].str()))
          includes.push_back(m[1]);
    }
  }
  return graph;
}

/// The layer of a file: its folder (accel's subfolders are layers of their own).
std::string layer_of(const std::string& file) {
  const auto slash = file.find('/');
  const std::string top = file.substr(0, slash);
  if (top != "accel") return top;
  const auto second = file.find('/', slash + 1);
  return second == std::string::npos ? "accel" : file.substr(0, second);
}

/// Rank of a layer: a file may include files of its own layer or of a lower rank, and a family only core,
/// common and itself.
int rank_of(const std::string& layer) {
  if (layer == "accel/core") return 0;
  if (layer == "accel/common") return 1;
  if (layer.rfind("accel/", 0) == 0) return 2;
  if (layer == "datasets") return 3;
  if (layer == "tracer") return 4;
  return 5;  // harness
}

bool allowed(const std::string& from, const std::string& to) {
  if (from == to) return true;
  if (from == "datasets") return to == "accel/core";
  const int rf = rank_of(from), rt = rank_of(to);
  if (rf == 2 && rt == 2) return false;  // families are independent of each other
  return rt < rf;
}

TEST(Layering, NoSourceFileSitsDirectlyInAccel) {
  for (const auto& [file, includes] : include_graph()) EXPECT_NE(layer_of(file), "accel") << file;
}

TEST(Layering, IncludesRunOneWay) {
  for (const auto& [file, includes] : include_graph())
    for (const std::string& inc : includes)
      EXPECT_TRUE(allowed(layer_of(file), layer_of(inc))) << file << " includes " << inc;
}

TEST(Layering, NoIncludeLoops) {
  const auto graph = include_graph();
  std::map<std::string, int> state;  // 1 on the path, 2 done
  std::vector<std::string> path;
  std::function<void(const std::string&)> visit = [&](const std::string& f) {
    state[f] = 1;
    path.push_back(f);
    const auto it = graph.find(f);
    if (it != graph.end())
      for (const std::string& g : it->second) {
        if (state[g] == 1) {
          std::string loop;
          for (const auto& p : path) loop += p + " -> ";
          ADD_FAILURE() << "include loop: " << loop << g;
        } else if (state[g] == 0) {
          visit(g);
        }
      }
    path.pop_back();
    state[f] = 2;
  };
  for (const auto& [file, includes] : graph)
    if (state[file] == 0) visit(file);
}

TEST(Layering, TheGraphIsNotEmpty) {
  const auto graph = include_graph();
  EXPECT_GT(graph.size(), 50u);
  EXPECT_TRUE(graph.count("accel/core/accelerator.h"));
}

}  // namespace
