// `accelbench list [--json]`: accelerators, mesh generators and ray kinds.
#include <iomanip>
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>

#include "accel/core/registry.h"
#include "datasets/generators.h"
#include "datasets/rays.h"
#include "harness/cli.h"
#include "harness/selection.h"
#include "tracer/workload.h"

namespace ab {
namespace {

nlohmann::json listing() {
  nlohmann::json j;
  j["accelerators"] = nlohmann::json::array();
  for (const auto& a : accelerators()) {
    if (is_test_only(a.name)) continue;
    j["accelerators"].push_back({{"name", a.name},
                                 {"description", a.description},
                                 {"reference", a.is_reference},
                                 {"top_level", static_cast<bool>(a.make_for_instances)},
                                 {"params", default_params(a.name)}});
  }
  j["generators"] = nlohmann::json::array();
  for (const auto& g : generators())
    j["generators"].push_back({{"name", g.name}, {"description", g.description}});
  j["ray_kinds"] = nlohmann::json::array();
  for (const auto& k : ray_kinds())
    j["ray_kinds"].push_back({{"name", k.name}, {"description", k.description}});
  j["scene_ray_kinds"] = nlohmann::json::array();
  for (const auto& k : scene_ray_kinds())
    j["scene_ray_kinds"].push_back({{"name", k.name}, {"description", k.description}});
  return j;
}

/// One line per item; items with parameters get a second line listing them with their defaults.
void print_section(const std::string& title, const nlohmann::json& items) {
  std::cout << title << ":\n";
  for (const auto& item : items) {
    std::cout << "  " << std::left << std::setw(16) << item["name"].get<std::string>() << " "
              << item["description"].get<std::string>() << "\n";
    if (!item.contains("params") || item["params"].empty()) continue;
    std::cout << std::string(2 + 16 + 1, ' ') << "params:";  // under the description
    for (const auto& [k, v] : item["params"].items())
      std::cout << " " << k << "=" << (v.is_string() ? v.get<std::string>() : v.dump());
    std::cout << "\n";
  }
}

const CommandRegistrar kList{{"list", "names of accelerators, mesh generators and ray kinds", 10,
                              [](CLI::App& app) -> std::function<int()> {
                                auto json = std::make_shared<bool>(false);
                                app.add_flag("--json", *json, "print as JSON");
                                return [json] {
                                  const nlohmann::json j = listing();
                                  if (*json) {
                                    std::cout << j.dump(2) << "\n";
                                  } else {
                                    print_section("accelerators", j["accelerators"]);
                                    print_section("generators", j["generators"]);
                                    print_section("ray kinds", j["ray_kinds"]);
                                    print_section("ray kinds for --scene (the tracer's own)",
                                                  j["scene_ray_kinds"]);
                                  }
                                  return 0;
                                };
                              }}};

}  // namespace
}  // namespace ab
