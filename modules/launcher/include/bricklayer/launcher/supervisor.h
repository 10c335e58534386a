// The launcher's supervisor: starts a profile's modules in order, reports each one up only when its
// heartbeat (heartbeat_t on BL_HEARTBEAT with the child's pid) arrives, restarts a module that dies
// or falls silent (counted, logged, BRICKLAYER_RESTARTS in its environment so its own heartbeat says
// so), runs bricklayer-logger, and stops everything with SIGTERM and a deadline, then SIGKILL.
//
// Subscribes: BL_HEARTBEAT (heartbeat_t). Publishes: BL_HEARTBEAT (its own, module "launcher").
#pragma once

#include <chrono>
#include <memory>
#include <string>
#include <vector>

#include "bricklayer/common/module.h"
#include "bricklayer/heartbeat_t.hpp"
#include "bricklayer/launcher/process.h"
#include "bricklayer/launcher/profile.h"

namespace bricklayer::launcher {

struct SupervisorOptions {
  std::string root;                   // working directory of every module; base of relative paths
  std::vector<std::string> bin_dirs;  // where bare program names are looked up first (then PATH)
  std::string lcm_url;                // resolved URL, given to every module as LCM_DEFAULT_URL
  double duration_s = 0;              // stop by itself after this long (0 = until SIGINT/SIGTERM)
  bool display = false;               // use command_with_display where a profile gives one
};

// What a profile would start on this host: every process (logger first) with its resolved command line.
struct LaunchPlan {
  struct Entry {
    ModuleSpec spec;
    std::vector<std::string> argv;
  };
  std::vector<Entry> processes;
  std::string log_file;  // "" without a logger
  std::string log_dir;
};

// Resolves every program; throws ProfileError naming each one that is missing (and the build target).
LaunchPlan plan_launch(const Profile& profile, const SupervisorOptions& options);

class Supervisor {
 public:
  // Resolves every program first; throws ProfileError naming each one that is missing, before
  // anything is started.
  Supervisor(Profile profile, SupervisorOptions options);
  ~Supervisor();

  // Runs until the duration elapses, a stop signal arrives, or a module fails to come up.
  // Returns 0 after a clean run, 1 when a module never came up.
  int run();

  const std::string& log_file() const { return log_file_; }

 private:
  using Clock = std::chrono::steady_clock;
  enum class State { kPending, kStarting, kUp, kWaitingRestart, kExited, kStopped };
  struct Managed {
    ModuleSpec spec;
    std::vector<std::string> argv;  // resolved program + arguments
    Process proc;
    State state = State::kPending;
    int restarts = 0;
    int quick_failures = 0;
    Clock::time_point started{};
    Clock::time_point last_beat{};
    Clock::time_point restart_at{};
    heartbeat_t last{};
    bool has_beat = false;
    std::string last_exit;
  };

  void HandleHeartbeat(const heartbeat_t& hb);
  void tick();
  void start(Managed& m);
  bool ready(const Managed& m) const;
  void shutdown();
  void print_summary() const;
  void say(const std::string& line) const;
  double since_start(Clock::time_point t) const;

  Profile profile_;
  SupervisorOptions options_;
  std::unique_ptr<Module> module_;
  std::vector<Managed> managed_;  // logger first (when any), then the profile's modules in order
  size_t next_to_start_ = 0;
  bool all_up_announced_ = false;
  bool fatal_ = false;
  std::string log_file_;
  std::string host_;  // this machine's name, as in heartbeat_t.instance ("host:pid")
  Clock::time_point t0_;
};

}  // namespace bricklayer::launcher
