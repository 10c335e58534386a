// The projector screen: whether a display server is reachable, how many displays it has, and the
// resolution of the one projection will fill (SDL2, as bricklayer-projection opens it).
#pragma once

#include <vector>

#include "bricklayer/doctor/check.h"
#include "bricklayer/doctor/host_plan.h"

namespace bricklayer::doctor {

std::vector<CheckResult> check_display(const HostPlan& plan);

}  // namespace bricklayer::doctor
