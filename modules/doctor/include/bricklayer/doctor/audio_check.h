// The beep: whether SDL2 can open an audio device that reaches a speaker, as bricklayer-projection
// does. Without one the exhibit runs silent (a warning, never a failure).
#pragma once

#include "bricklayer/doctor/check.h"
#include "bricklayer/doctor/host_plan.h"

namespace bricklayer::doctor {

CheckResult check_audio(const HostPlan& plan);

}  // namespace bricklayer::doctor
