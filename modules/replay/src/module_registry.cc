#include "bricklayer/replay/module_registry.h"

#include <stdexcept>

#include "bricklayer/common/channels.h"
#include "bricklayer/planner/planner_node.h"
#include "bricklayer/prediction/prediction_node.h"
#include "bricklayer/vision/vision_node.h"

namespace bricklayer::replay {

const std::vector<ModuleAdapter>& replayable_modules() {
  static const std::vector<ModuleAdapter> modules = [] {
    std::vector<ModuleAdapter> m;
    m.push_back(node_adapter<vision::VisionNode>("vision", {channel(kStackChannel)}));
    m.push_back(node_adapter<prediction::PredictionNode>("prediction", {channel(kPredictionChannel)}));
    m.push_back(node_adapter<planner::PlannerNode>("planner", {channel(kPreviewChannel), channel(kHintChannel)}));
    return m;
  }();
  return modules;
}

std::string replayable_names() {
  std::string out;
  for (const auto& m : replayable_modules()) out += (out.empty() ? "" : ", ") + m.name;
  return out;
}

const ModuleAdapter& module_named(const std::string& name) {
  for (const auto& m : replayable_modules())
    if (m.name == name) return m;
  throw std::invalid_argument("no module '" + name + "' to replay in this build (available: " + replayable_names() + ")");
}

}  // namespace bricklayer::replay
