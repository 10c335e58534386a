#include "bricklayer/doctor/display_check.h"

#include <SDL.h>

#include <cstdlib>
#include <string>

namespace bricklayer::doctor {
namespace {

std::string env(const char* name) {
  const char* v = std::getenv(name);
  return v ? v : "";
}

std::string mode_text(const SDL_DisplayMode& m) {
  return std::to_string(m.w) + "x" + std::to_string(m.h) + (m.refresh_rate > 0 ? " at " + std::to_string(m.refresh_rate) + " Hz" : "");
}

}  // namespace

std::vector<CheckResult> check_display(const HostPlan& plan) {
  const std::string name = "display";
  if (!plan.projection) return {CheckResult::ok(name, "profile " + plan.profile + " runs no projection")};
  if (plan.display == DisplayNeed::kNone) return {CheckResult::ok(name, "projection runs headless (snapshots only)")};
  const bool required = plan.display == DisplayNeed::kFullscreen;
  auto missing = [&](const std::string& detail, const std::string& fix) {
    return required ? CheckResult::failed(name, detail, fix) : CheckResult::warning(name, detail + ": projection falls back to snapshots", fix);
  };
  // A video driver without a screen would satisfy SDL but show nothing to anyone.
  const std::string driver = env("SDL_VIDEODRIVER");
  if (driver == "offscreen" || driver == "dummy")
    return {missing("SDL_VIDEODRIVER=" + driver + " shows nothing on a screen", "unset SDL_VIDEODRIVER")};
  if (env("DISPLAY").empty() && env("WAYLAND_DISPLAY").empty())
    return {missing("no display server ($DISPLAY and $WAYLAND_DISPLAY unset)",
                    "run from the desktop session of the exhibit's user, or export DISPLAY=:0 (see docs/hardware.md)")};
  if (SDL_InitSubSystem(SDL_INIT_VIDEO) != 0)
    return {missing(std::string("cannot open the display ") + env("DISPLAY") + ": " + SDL_GetError(),
                    "check that the X server runs and this user may use it (xhost, XAUTHORITY)")};
  std::vector<CheckResult> out;
  const int count = SDL_GetNumVideoDisplays();
  std::string list;
  for (int i = 0; i < count; ++i) {
    SDL_DisplayMode m{};
    if (SDL_GetCurrentDisplayMode(i, &m) == 0) list += (list.empty() ? "" : ", ") + std::to_string(i) + ": " + mode_text(m);
  }
  const std::string found = std::to_string(count) + (count == 1 ? " display (" : " displays (") + list + ")";
  if (plan.display == DisplayNeed::kOptional) {
    out.push_back(CheckResult::ok(name, found + "; projection opens a window"));
  } else if (plan.display_index >= count) {
    out.push_back(CheckResult::failed(name, "projection wants display " + std::to_string(plan.display_index) + ", " + found,
                                      "connect the projector and extend the desktop onto it (not mirrored), or change --display in the profile"));
  } else {
    SDL_DisplayMode m{};
    SDL_GetCurrentDisplayMode(plan.display_index, &m);
    SDL_Rect own{}, other{};
    SDL_GetDisplayBounds(plan.display_index, &own);
    bool mirrored = false;
    for (int i = 0; i < count; ++i)
      if (i != plan.display_index && SDL_GetDisplayBounds(i, &other) == 0 && other.x == own.x && other.y == own.y) mirrored = true;
    const std::string size = std::to_string(plan.projector_width) + "x" + std::to_string(plan.projector_height);
    const std::string which = "display " + std::to_string(plan.display_index) + " is " + mode_text(m);
    if (mirrored) {
      out.push_back(CheckResult::warning(name, which + " and mirrors another display: " + found,
                                         "extend the desktop (xrandr --output PROJECTOR --right-of PRIMARY)"));
    } else if (m.w != plan.projector_width || m.h != plan.projector_height) {
      out.push_back(CheckResult::warning(name, which + ", projection draws " + size + " and is scaled to fit",
                                         "set the projector's output to " + size + " (xrandr --output PROJECTOR --mode " + size +
                                             "), or give projection --width/--height of the display and recalibrate"));
    } else {
      out.push_back(CheckResult::ok(name, which + ", as projection draws; " + found));
    }
  }
  SDL_QuitSubSystem(SDL_INIT_VIDEO);
  return out;
}

}  // namespace bricklayer::doctor
