// bricklayer-doctor [PROFILE]: is this host ready for the exhibit? One line per check (ok, warning or
// FAILED with the fix): the bus URL, multicast route and loopback, receive buffers for LAN use, the
// projector's display, audio, fonts, the camera (size, rate, lockable automatic modes), disk space
// for the log, the clock offset to the other host (from heartbeats), and the calibration file.
// Exit 0 when nothing would stop the exhibit (warnings allowed), 1 when something would, 2 for bad
// flags or a bad profile.
// Subscribes: BL_HEARTBEAT (clock check). Publishes: BL_HEARTBEAT ("doctor", during the clock check),
//             a private loopback channel (bus loopback check).
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <functional>
#include <iostream>
#include <set>
#include <sstream>

#include "bricklayer/common/flags.h"
#include "bricklayer/common/lcm_url.h"
#include "bricklayer/common/log.h"
#include "bricklayer/doctor/audio_check.h"
#include "bricklayer/doctor/bus_checks.h"
#include "bricklayer/doctor/calibration_check.h"
#include "bricklayer/doctor/camera_check.h"
#include "bricklayer/doctor/check.h"
#include "bricklayer/doctor/clock_check.h"
#include "bricklayer/doctor/disk_check.h"
#include "bricklayer/doctor/display_check.h"
#include "bricklayer/doctor/font_check.h"
#include "bricklayer/doctor/host_plan.h"

namespace {

using namespace bricklayer;
using namespace bricklayer::doctor;
namespace fs = std::filesystem;

const std::vector<std::string> kGroups = {"bus", "display", "audio", "fonts", "camera", "disk", "clock", "calibration"};

fs::path self_dir() {
  std::error_code ec;
  fs::path exe = fs::read_symlink("/proc/self/exe", ec);
  return ec ? fs::current_path() : exe.parent_path();
}

std::set<std::string> parse_groups(const std::string& text) {
  std::set<std::string> out;
  std::stringstream in(text);
  std::string g;
  while (std::getline(in, g, ',')) {
    if (g.empty()) continue;
    if (std::find(kGroups.begin(), kGroups.end(), g) == kGroups.end()) {
      std::string list;
      for (const auto& k : kGroups) list += (list.empty() ? "" : ", ") + k;
      throw FlagError("--checks: unknown check '" + g + "' (expected some of " + list + ")");
    }
    out.insert(g);
  }
  return out;
}

double positive(const Flags& flags, const std::string& name, double max) {
  const double v = flags.get_double(name);
  if (!(v > 0 && v <= max)) throw FlagError("--" + name + " must be in (0, " + std::to_string(static_cast<int>(max)) + "]");
  return v;
}

int Main(int argc, char** argv) {
  Flags flags("bricklayer-doctor",
              "Checks whether this host is ready to run a profile of the exhibit and prints one line per check:\n"
              "ok, warning (runs, but worse) or FAILED (would not run), each with its fix. Exit 1 when a check failed.\n"
              "PROFILE is a name in ROOT/launch/profiles/ or a path to a .json file (default all-in-one).");
  flags.add_positional("profile", "the launch profile to check for", false);
  flags.add("root", "", "project root (default: found from this binary)");
  flags.add("lcm-url", "", "the URL the exhibit will use (default: LCM_DEFAULT_URL, else host-only ttl=0)");
  flags.add("checks", "", "only these, comma-separated: bus, display, audio, fonts, camera, disk, clock, calibration");
  flags.add("listen-s", "3", "clock: seconds to listen for the other host's heartbeats");
  flags.add("loopback-timeout-s", "1", "bus: seconds to wait for our own message to come back");
  flags.add("camera-seconds", "1.5", "camera: seconds over which a live camera's frame rate is measured");
  flags.add("wanted-fps", "30", "camera: the frame rate below which it warns (when the profile sets no --fps)");
  flags.add("save-frame", "", "camera: write the first frame to this file (does the view cover the board?)");
  flags.add("min-free-mb", "1024", "disk: free space that must remain beyond the log's budget, MB");
  flags.add("calibration-max-age-days", "30", "calibration: older than this is a warning");
  flags.add("log-level", "warn", "debug, info, warn or error");
  if (!flags.parse(argc, argv)) return 0;
  log::set_level(log::parse_level(flags.get("log-level")));

  fs::path root = flags.get("root");
  if (root.empty()) {
    root = fs::current_path();
    for (fs::path p = self_dir(); !p.empty() && p != p.root_path(); p = p.parent_path())
      if (fs::exists(p / "launch" / "profiles")) {
        root = p;
        break;
      }
  }
  root = fs::absolute(root);
  const std::string name = flags.positional().empty() ? "all-in-one" : flags.positional().at(0);
  const fs::path profile_path = (name.find('/') != std::string::npos || fs::path(name).extension() == ".json")
                                    ? fs::path(name)
                                    : root / "launch" / "profiles" / (name + ".json");
  launcher::Profile profile;
  try {
    profile = launcher::load_profile(profile_path.string());
  } catch (const launcher::ProfileError& e) {
    throw FlagError(e.what());
  }
  const std::string url = resolve_lcm_url(flags.get("lcm-url"));
  const HostPlan plan = plan_host(profile, root.string(), url);
  std::set<std::string> groups = parse_groups(flags.get("checks"));
  if (groups.empty()) groups.insert(kGroups.begin(), kGroups.end());
  const double listen_s = positive(flags, "listen-s", 60);
  const double loopback_s = positive(flags, "loopback-timeout-s", 30);
  CameraCheckOptions camera_options;
  camera_options.measure_s = positive(flags, "camera-seconds", 30);
  camera_options.wanted_fps = positive(flags, "wanted-fps", 240);
  camera_options.save_frame = flags.get("save-frame");
  const double min_free_mb = flags.get_double("min-free-mb");
  if (min_free_mb < 0) throw FlagError("--min-free-mb must be >= 0");
  const double max_age_days = positive(flags, "calibration-max-age-days", 3650);

  std::cout << "bricklayer-doctor: profile " << plan.profile << " (" << profile_path.string() << ") on " << own_host_name()
            << (plan.two_hosts ? ", one of two hosts" : "") << std::endl;
  std::vector<CheckResult> results;
  auto report = [&](CheckResult r) {
    std::cout << format_line(r) << std::endl;  // as it comes: the camera and clock checks take seconds
    results.push_back(std::move(r));
  };
  auto report_all = [&](std::vector<CheckResult> rs) {
    for (auto& r : rs) report(std::move(r));
  };
  if (groups.count("bus")) {
    report(check_bus_url(plan));
    report(check_multicast_route(plan));
    report(check_bus_loopback(plan, loopback_s));
    report(check_receive_buffers(plan));
  }
  if (groups.count("display")) report_all(check_display(plan));
  if (groups.count("audio")) report(check_audio(plan));
  if (groups.count("fonts")) report(check_font(plan));
  if (groups.count("camera")) report_all(check_camera(plan, camera_options));
  if (groups.count("disk")) report(check_disk(budget_from_plan(plan, static_cast<uint64_t>(min_free_mb * 1048576))));
  if (groups.count("clock")) {
    if (plan.two_hosts) {
      try {
        report(judge_clock(plan, estimate_offsets(listen_heartbeats(url, listen_s), own_host_name()), listen_s));
      } catch (const std::exception& e) {
        report(CheckResult::warning("clock", std::string("cannot listen on the bus: ") + e.what(), "see the bus checks"));
      }
    } else {
      report(judge_clock(plan, {}, 0));
    }
  }
  if (groups.count("calibration")) {
    // The file's age is judged against this host's wall clock: the doctor is a tool, not a node.
    const int64_t now = std::chrono::duration_cast<std::chrono::microseconds>(std::chrono::system_clock::now().time_since_epoch()).count();
    report(check_calibration(plan, now, max_age_days));
  }

  const int code = exit_code(results);
  std::cout << summary(results) << (code ? ": the exhibit would not run" : ": ready") << std::endl;
  return code;
}

}  // namespace

int main(int argc, char** argv) { return bricklayer::run_main("bricklayer-doctor", &Main, argc, argv); }
