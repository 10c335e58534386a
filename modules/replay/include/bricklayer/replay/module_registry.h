// The modules this build can replay, each as its real node (module_adapter.h). A module joins the list
// when its process runs on the node runtime.
#pragma once

#include <string>
#include <vector>

#include "bricklayer/replay/module_adapter.h"

namespace bricklayer::replay {

const std::vector<ModuleAdapter>& replayable_modules();
// The adapter named so; throws std::invalid_argument naming the available ones.
const ModuleAdapter& module_named(const std::string& name);
// "prediction, planner"
std::string replayable_names();

}  // namespace bricklayer::replay
