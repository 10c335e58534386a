// The calibration file the profile serves: present, valid, made for this projector size, and fresh.
#pragma once

#include <cstdint>

#include "bricklayer/doctor/check.h"
#include "bricklayer/doctor/host_plan.h"

namespace bricklayer::doctor {

// now_utime: the time to judge the file's age against (the doctor passes the wall clock).
CheckResult check_calibration(const HostPlan& plan, int64_t now_utime, double max_age_days);

}  // namespace bricklayer::doctor
