// The font projection draws the score with: bricklayer-projection stops when it cannot load it.
#pragma once

#include "bricklayer/doctor/check.h"
#include "bricklayer/doctor/host_plan.h"

namespace bricklayer::doctor {

CheckResult check_font(const HostPlan& plan);

}  // namespace bricklayer::doctor
