// The strategies' names (apart from the strategies themselves, so parsers link without the structures).
#include "accel/core/error.h"
#include "tracer/update_strategy.h"

namespace ab {

const std::vector<UpdateStrategy>& all_update_strategies() {
  static const std::vector<UpdateStrategy> all{UpdateStrategy::kRebuild, UpdateStrategy::kRefit,
                                               UpdateStrategy::kAdaptive, UpdateStrategy::kTopLevel};
  return all;
}

std::string strategy_name(UpdateStrategy strategy) {
  switch (strategy) {
    case UpdateStrategy::kRebuild:
      return "rebuild";
    case UpdateStrategy::kRefit:
      return "refit";
    case UpdateStrategy::kAdaptive:
      return "adaptive";
    case UpdateStrategy::kTopLevel:
      return "top-level";
  }
  return "rebuild";
}

UpdateStrategy parse_strategy(const std::string& name) {
  for (UpdateStrategy s : all_update_strategies())
    if (strategy_name(s) == name) return s;
  throw ParamError("strategy '" + name + "' is not one of rebuild, refit, adaptive, top-level");
}

}  // namespace ab
