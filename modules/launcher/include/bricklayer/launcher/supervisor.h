// The launcher's supervisor: starts a profile's modules in order, reports each one up only when its
// heartbeat (heartbeat_t on BL_HEARTBEAT with the child's pid) arrives, restarts a module that dies
// or falls silent (counted, logged, BRICKLAYER_RESTARTS in its environment so its own heartbeat says
// so), runs bricklayer-logger, and stops everything with SIGTERM and a deadline, then SIGKILL.
//
// It never gives up on a profile: a module that cannot start (exits at once, never sends its first
// heartbeat) is retried with a backoff capped at its backoff_max_s while the rest of the start order
// goes on, and the output, the summary and the host state say exactly what is down. A module is judged
// silent only while the launcher hears its own heartbeat: with the bus itself down (an interface
// down and up) nothing is killed for a silence nobody could have heard.
//
// It also listens to the other hosts' launchers: a host whose state stops arriving (the other machine
// off, the link cut) is named in this host's status ("no host state from projector-host for 7 s")
// until it is heard again; a host whose last message said it stopped is not missed.
//
// Subscribes: BL_HEARTBEAT (heartbeat_t), BL_HOST_STATE (host_state_t, the other hosts'), BL_COMMAND
//             (command_t RESTART_MODULE "HOST/NAME" for this host: the module is stopped with SIGTERM and
//             started again at once, whatever its restart policy; one in its backoff or failed starts now).
// Publishes:  BL_HEARTBEAT (its own, module "launcher"); BL_HOST_STATE (host_state_t, once a second:
//             every module's state, pid, restarts, uptime, counters summed across restarts, status).
//
// The profile's opening hours and nightly restart (opening_hours.h) are read against the local wall
// clock: outside the hours every module but the logger and those with "when_closed": "run" is stopped
// (SIGTERM, the stop deadline, SIGKILL) and shown waiting, "closed until 09:30", in the host state and the
// launcher's heartbeat; at opening they start again in order. At the nightly restart time every running
// process is stopped with SIGTERM and started again at once, as an operator's RESTART_MODULE does.
#pragma once

#include <chrono>
#include <functional>
#include <map>
#include <set>
#include <memory>
#include <string>
#include <vector>

#include "bricklayer/command_t.hpp"
#include "bricklayer/heartbeat_t.hpp"
#include "bricklayer/host_state_t.hpp"
#include "bricklayer/launcher/opening_hours.h"
#include "bricklayer/launcher/process.h"
#include "bricklayer/launcher/profile.h"

namespace bricklayer::runtime {
class LcmBus;
}

namespace bricklayer::launcher {

// host_state_t's channel (before the deployment's prefix: use channel(kHostStateChannel)).
inline constexpr const char* kHostStateChannel = "BL_HOST_STATE";

struct SupervisorOptions {
  std::string root;                   // working directory of every module; base of relative paths
  std::vector<std::string> bin_dirs;  // where bare program names are looked up first (then PATH)
  std::string lcm_url;                // resolved URL, given to every module as LCM_DEFAULT_URL
  double duration_s = 0;              // stop by itself after this long (0 = until SIGINT/SIGTERM)
  bool display = false;               // use command_with_display where a profile gives one
  std::string host_name;              // host_state_t.host; "" = gethostname()
  // The interface of the multicast route (224.0.0.0/4) the launcher puts back while its bus is down
  // (an interface that went down and up loses it); "" = leave routes alone. Needs CAP_NET_ADMIN.
  std::string multicast_route_dev;
  // The local wall clock the opening hours and the nightly restart are read against; empty = the
  // machine's local time. Tests give a clock that starts where they want and runs faster.
  std::function<LocalTime()> local_clock;
  double local_clock_speed = 1;  // local seconds per real second of local_clock (for "restart in" times)
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

  // Runs until the duration elapses or a stop signal arrives. Returns 0 when every module was up (or
  // had ended as its restart policy allows) at the stop, 1 when one was down.
  int run();

  const std::string& log_file() const { return log_file_; }
  // The host state as published now.
  host_state_t host_state() const;

 private:
  class SupervisorNode;
  using Clock = std::chrono::steady_clock;
  // kClosed: stopped, or never started, because the exhibit is closed (opening hours); starts at opening.
  enum class State { kPending, kStarting, kUp, kWaitingRestart, kFailed, kExited, kStopped, kClosed };
  struct Totals {
    int64_t received = 0, published = 0, dropped = 0, errors = 0;
  };
  struct Managed {
    ModuleSpec spec;
    std::vector<std::string> argv;  // resolved program + arguments
    Process proc;
    State state = State::kPending;
    int restarts = 0;
    int quick_failures = 0;
    bool start_failed = false;  // ended or timed out before its first heartbeat: the start order moved on
    Clock::time_point started{};
    Clock::time_point last_beat{};
    Clock::time_point restart_at{};
    heartbeat_t last{};
    bool has_beat = false;
    Totals before;              // counters of the earlier processes of this module
    std::string last_exit;
    bool restart_requested = false;  // the operator asked for a restart: the reap restarts it at once
    bool closing = false;            // SIGTERM sent at closing time: the reap puts it to kClosed
    Clock::time_point close_deadline{};
  };

  void HandleHeartbeat(const heartbeat_t& hb);
  void HandleHostState(const host_state_t& hs);
  void HandleCommand(const command_t& c);
  std::string silent_peers(Clock::time_point now) const;
  void tick();
  void before_heartbeat();
  void start(Managed& m);
  void ended(Managed& m, Clock::time_point now);
  bool ready(const Managed& m) const;
  bool settled(const Managed& m) const;
  bool bus_heard(Clock::time_point now) const;
  void repair_route(Clock::time_point now);
  void follow_schedule(Clock::time_point now);
  LocalTime local_now() const;
  bool closes(const Managed& m) const { return !m.spec.run_when_closed; }
  std::string down_summary() const;
  std::string status_of(const Managed& m, Clock::time_point now) const;
  Totals totals(const Managed& m) const;
  void shutdown();
  void print_summary() const;
  void say(const std::string& line) const;
  double since_start(Clock::time_point t) const;

  Profile profile_;
  SupervisorOptions options_;
  std::unique_ptr<runtime::LcmBus> bus_;
  std::unique_ptr<SupervisorNode> node_;
  std::vector<Managed> managed_;  // logger first (when any), then the profile's modules in order
  size_t next_to_start_ = 0;
  bool all_up_announced_ = false;
  bool shutting_down_ = false;
  std::string announced_down_;  // the last "what is down" line said, so a change is said once
  std::string log_file_;
  std::string host_;        // this machine's name, as in heartbeat_t.instance ("host:pid")
  std::string host_label_;  // host_state_t.host
  Clock::time_point t0_;
  Clock::time_point last_self_heard_{};  // the launcher's own heartbeat, heard back on the bus
  bool bus_was_deaf_ = false;
  struct Peer {
    Clock::time_point last_seen;
    bool stopped = false;  // its last message had every module stopped: it shut down on purpose
  };
  std::map<std::string, Peer> peers_;  // other hosts, by host_state_t.host
  std::set<std::string> now_silent_;   // the hosts whose silence has been said
  Clock::time_point next_route_repair_{};
  int64_t unknown_commands_ = 0;  // restarts asked for a module this host does not run
  bool open_ = true;              // within the opening hours at the last tick
  bool schedule_started_ = false; // the first tick has read the clock (prev_local_ is set)
  LocalTime prev_local_{};        // the local clock at the previous tick: the nightly restart fires between two
  int nightly_restarts_ = 0;
};

}  // namespace bricklayer::launcher
