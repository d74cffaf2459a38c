#include "harness/selection.h"

#include <algorithm>
#include <sstream>

#include "accel/core/registry.h"

namespace ab {

bool is_test_only(const std::string& name) {
  return name.rfind("test-", 0) == 0;
}

bool is_registered(const std::string& name) {
  const auto& all = accelerators();
  return std::any_of(all.begin(), all.end(), [&](const AcceleratorInfo& a) { return a.name == name; });
}

std::vector<std::string> listed_accelerators(const std::set<std::string>& excluded) {
  std::vector<std::string> names;
  for (const auto& info : accelerators())
    if (!is_test_only(info.name) && !excluded.count(info.name)) names.push_back(info.name);
  return names;
}

std::string default_structure() {
  return is_registered("bvh-sah") ? "bvh-sah" : "brute";
}

std::vector<std::string> split_list(const std::string& text) {
  std::vector<std::string> items;
  std::stringstream ss(text);
  for (std::string item; std::getline(ss, item, ',');) items.push_back(item);
  return items;
}

}  // namespace ab
