// bricklayer-launch: starts one host's set of Bricklayer processes from a declarative profile
// (launch/profiles/<name>.json), waits for each one's heartbeat, restarts what dies, runs bricklayer-logger,
// and stops everything cleanly. Usually started through launch/bricklayer PROFILE.
//
// Subscribes: BL_HEARTBEAT (heartbeat_t). Publishes: BL_HEARTBEAT (module "launcher").
#include <unistd.h>

#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <iostream>

#include "bricklayer/common/flags.h"
#include "bricklayer/common/lcm_url.h"
#include "bricklayer/common/log.h"
#include "bricklayer/launcher/opening_hours.h"
#include "bricklayer/launcher/profile.h"
#include "bricklayer/launcher/profile_check.h"
#include "bricklayer/launcher/supervisor.h"

namespace {

namespace fs = std::filesystem;
using namespace bricklayer;

fs::path self_dir() {
  std::error_code ec;
  fs::path exe = fs::read_symlink("/proc/self/exe", ec);
  return ec ? fs::current_path() : exe.parent_path();
}

int Main(int argc, char** argv) {
  Flags flags("bricklayer-launch",
              "Starts the processes of a launch profile in order, reports each one up when its heartbeat arrives,\n"
              "restarts any that dies (counted; BRICKLAYER_RESTARTS is passed on), records the bus with bricklayer-logger\n"
              "into logs/, and on Ctrl-C / SIGTERM / --duration stops everything (SIGTERM, deadline, SIGKILL)\n"
              "and prints a summary. PROFILE is a name in ROOT/launch/profiles/ or a path to a .json file.");
  flags.add_positional("PROFILE", "profile name (demo, all-in-one, camera-host, projector-host) or file");
  flags.add("root", "", "project root: working directory of every module (default: found from this binary)");
  flags.add("bin-dir", "", "where bare program names are looked up before PATH (default: this binary's directory)");
  flags.add("duration", "", "stop by itself after this many seconds (default: the profile's; 0 = until Ctrl-C)");
  flags.add("lcm-url", "", "LCM URL for every module (default: LCM_DEFAULT_URL, else host-only ttl=0)");
  flags.add("log-level", "info", "debug, info, warn or error");
  flags.add("host-name", "", "this host's name in the host state on BL_HOST_STATE (default: the machine's name)");
  flags.add("multicast-route", "",
            "interface (lo, eth0) whose multicast route 224.0.0.0/4 the launcher puts back while its bus hears nothing "
            "(an interface that went down and up loses it); needs CAP_NET_ADMIN. Default: the profile's multicast_route, "
            "else leave routes alone");
  flags.add_bool("check", "only check the profile: print what would be started and check every file its modules will "
                          "read; exit 2 if a binary or a file is missing");
  if (!flags.parse(argc, argv)) return 0;
  log::set_level(log::parse_level(flags.get("log-level")));

  fs::path bin = flags.get("bin-dir").empty() ? self_dir() : fs::path(flags.get("bin-dir"));
  fs::path root = flags.get("root");
  if (root.empty()) {
    root = fs::current_path();
    for (fs::path p = bin; !p.empty() && p != p.root_path(); p = p.parent_path()) {
      if (fs::exists(p / "launch" / "profiles")) {
        root = p;
        break;
      }
    }
  }
  root = fs::absolute(root);

  std::string name = flags.positional().at(0);
  fs::path profile_path = (name.find('/') != std::string::npos || fs::path(name).extension() == ".json")
                              ? fs::path(name)
                              : root / "launch" / "profiles" / (name + ".json");
  launcher::Profile profile;
  try {
    profile = launcher::load_profile(profile_path.string());
  } catch (const launcher::ProfileError& e) {
    throw FlagError(e.what());
  }

  launcher::SupervisorOptions options;
  options.root = root.string();
  options.bin_dirs = {fs::absolute(bin).string()};
  options.lcm_url = resolve_lcm_url(flags.get("lcm-url"));
  options.host_name = flags.get("host-name");
  // The profile names its LAN interface; --multicast-route overrides it ("" leaves routes alone).
  options.multicast_route_dev = flags.was_set("multicast-route") ? flags.get("multicast-route") : profile.multicast_route;
  // For tests only: the opening hours and the nightly restart read this clock instead of the machine's
  // local time ("[DAY ]HH:MM:SS[ xSPEED]", opening_hours.h), so a test lives through a closing time in seconds.
  if (const char* clock = std::getenv("BRICKLAYER_LAUNCHER_CLOCK"); clock && *clock) {
    launcher::TestClock test_clock;
    try {
      test_clock = launcher::parse_test_clock(clock);
    } catch (const std::invalid_argument& e) {
      throw FlagError(e.what());
    }
    const auto t0 = std::chrono::steady_clock::now();
    options.local_clock = [test_clock, t0] {
      const double real = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
      return launcher::advance(test_clock.start, static_cast<int64_t>(real * test_clock.speed));
    };
    options.local_clock_speed = test_clock.speed;
  }
  try {
    check_lcm_url(options.lcm_url);
  } catch (const std::invalid_argument& e) {
    throw FlagError(e.what());
  }
  const char* display = std::getenv("DISPLAY");
  options.display = display && *display;
  options.duration_s = profile.duration_s;
  if (options.duration_s == 0 && !options.display) options.duration_s = profile.headless_duration_s;
  if (flags.was_set("duration")) {
    options.duration_s = flags.get_double("duration");
    if (options.duration_s < 0) throw FlagError("--duration must be >= 0 seconds");
  }

  if (flags.get_bool("check")) {
    try {
      launcher::LaunchPlan plan = launcher::plan_launch(profile, options);
      std::cout << "profile " << profile.name << ": " << plan.processes.size() << " processes, in start order\n";
      for (const auto& [spec, command] : plan.processes) {
        std::cout << "  " << spec.name << " (" << (spec.heartbeat.empty() ? "no heartbeat" : "heartbeat " + spec.heartbeat)
                  << ", restart " << launcher::to_string(spec.restart) << "):";
        for (const auto& a : command) std::cout << " " << a;
        std::cout << "\n";
      }
      if (!plan.log_file.empty()) std::cout << "  bus log: " << plan.log_file << "\n";
      std::cout << "  duration: ";
      if (options.duration_s > 0)
        std::cout << options.duration_s << " s\n";
      else
        std::cout << "until Ctrl-C\n";
      std::cout << "  opening hours: "
                << (profile.opening_hours.always_open() ? std::string("always open") : profile.opening_hours.text() + " (local time)")
                << "\n";
      if (profile.nightly_restart >= 0)
        std::cout << "  nightly restart: " << launcher::clock_text(profile.nightly_restart) << " (local time)\n";
      if (!options.multicast_route_dev.empty())
        std::cout << "  multicast route: " << options.multicast_route_dev << " (needs CAP_NET_ADMIN)\n";
      const launcher::FileCheckReport files = launcher::check_module_files(plan, options);
      std::cout << "files:\n";
      for (const auto& note : files.notes) std::cout << "  " << note << "\n";
      if (!files.problems.empty()) {
        std::string msg = "profile " + profile.name + " cannot run as it is:";
        for (const auto& p : files.problems) msg += "\n  " + p;
        throw launcher::ProfileError(msg);
      }
    } catch (const launcher::ProfileError& e) {
      throw FlagError(e.what());
    }
    return 0;
  }

  std::unique_ptr<launcher::Supervisor> supervisor;
  try {
    supervisor = std::make_unique<launcher::Supervisor>(profile, options);
  } catch (const launcher::ProfileError& e) {
    throw FlagError(e.what());
  }
  return supervisor->run();
}

}  // namespace

int main(int argc, char** argv) { return bricklayer::run_main("bricklayer-launch", &Main, argc, argv); }
