#include "bricklayer/launcher/supervisor.h"

#include <signal.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <filesystem>
#include <iostream>
#include <sstream>

#include "bricklayer/common/channels.h"
#include "bricklayer/common/log.h"
#include "bricklayer/runtime/lcm_bus.h"
#include "bricklayer/runtime/node.h"

namespace bricklayer::launcher {
namespace {

namespace fs = std::filesystem;

std::string format_seconds(double s) {
  char buf[32];
  std::snprintf(buf, sizeof(buf), "%.1f", s);
  return buf;
}

std::string strftime_now(const std::string& pattern) {
  std::time_t t = std::time(nullptr);
  std::tm tm{};
  localtime_r(&t, &tm);
  char buf[1024];
  size_t n = std::strftime(buf, sizeof(buf), pattern.c_str(), &tm);
  return n ? std::string(buf, n) : pattern;
}

std::chrono::microseconds seconds(double s) { return std::chrono::microseconds(static_cast<int64_t>(s * 1e6)); }

// The launcher's own heartbeat is heard back within a second on a working bus; after this long without
// it the bus is deaf (an interface down, no route), and no module is judged by its silence.
constexpr auto kDeafAfter = std::chrono::milliseconds(2500);
// Another host's launcher publishes its state once a second; silent this long, it is missed.
constexpr auto kPeerSilentAfter = std::chrono::seconds(5);

}  // namespace

LaunchPlan plan_launch(const Profile& profile, const SupervisorOptions& options) {
  LaunchPlan plan;
  std::vector<std::string> missing;
  auto resolve = [&](const std::string& who, std::vector<std::string> argv) {
    std::string path = find_program(argv[0], options.root, options.bin_dirs);
    if (path.empty()) {
      std::string where;
      for (const auto& d : options.bin_dirs) where += d + ", ";
      missing.push_back("module '" + who + "' needs '" + argv[0] + "', which was not found (looked in " + where +
                        "then PATH; not built yet? cmake --build " +
                        (options.bin_dirs.empty() ? std::string("build")
                                                  : fs::path(options.bin_dirs.front()).parent_path().string()) +
                        " --target " + fs::path(argv[0]).filename().string() + ")");
    }
    argv[0] = path;
    return argv;
  };
  if (profile.logger) {
    const LoggerSpec& l = *profile.logger;
    std::string file = strftime_now(l.file);
    fs::path full = fs::path(file).is_absolute() ? fs::path(file) : fs::path(options.root) / file;
    // bricklayer-logger (modules/logger): lcm-logger's file naming, without its silent 30-message
    // queue; the profile's budget and frame policy as its flags.
    std::vector<std::string> argv = {"bricklayer-logger", "--lcm-url=" + options.lcm_url};
    for (auto& a : logger_arguments(l, full.string())) argv.push_back(std::move(a));
    plan.log_file = full.string() + (l.rotate > 0 ? ".0" : ".*");
    ModuleSpec spec;
    spec.name = "logger";
    // Up only once its heartbeat arrives: it is subscribed by then, so the modules started after it
    // are recorded from their first message.
    spec.heartbeat = "logger";
    spec.restart = RestartPolicy::kAlways;
    // It keeps recording while the exhibit is closed: the closing, the opening, the host states.
    spec.run_when_closed = true;
    plan.processes.push_back({spec, resolve("logger", argv)});
  }
  for (const auto& spec : profile.modules) {
    const auto& cmd = (options.display && !spec.command_with_display.empty()) ? spec.command_with_display : spec.command;
    plan.processes.push_back({spec, resolve(spec.name, cmd)});
  }
  if (!missing.empty()) {
    std::string msg = "profile " + profile.name + " cannot start:";
    for (const auto& line : missing) msg += "\n  " + line;
    throw ProfileError(msg);
  }
  return plan;
}

// The launcher on the bus: a runtime node (so its bus heals like every module's), with the supervisor's
// work in tick() and the host state published with each heartbeat.
class Supervisor::SupervisorNode final : public runtime::Node {
 public:
  SupervisorNode(Supervisor& owner, runtime::Bus& bus) : Node("launcher", bus), owner_(owner) {
    // Every module's heartbeat matters: a generous queue, not newest-wins.
    subscribe<heartbeat_t>(channel(kHeartbeatChannel), runtime::QueuePolicy::keep(4096),
                           [this](const heartbeat_t& hb) { owner_.HandleHeartbeat(hb); });
    subscribe<host_state_t>(channel(kHostStateChannel), runtime::QueuePolicy::keep(256),
                            [this](const host_state_t& hs) { owner_.HandleHostState(hs); });
    // Operator commands (the status page's "restart"); every one counts, so a queue.
    subscribe<command_t>(channel(kCommandChannel), runtime::QueuePolicy::keep(64),
                         [this](const command_t& c) { owner_.HandleCommand(c); });
    set_tick_ms(20);
  }
  using Node::publish_report;
  using Node::set_status;
  using Node::set_value;
  using Node::warn;

 private:
  void tick() override { owner_.tick(); }
  void before_heartbeat() override { owner_.before_heartbeat(); }
  Supervisor& owner_;
};

Supervisor::Supervisor(Profile profile, SupervisorOptions options)
    : profile_(std::move(profile)), options_(std::move(options)) {
  LaunchPlan plan = plan_launch(profile_, options_);
  log_file_ = plan.log_file;
  if (!plan.log_dir.empty()) {
    std::error_code ec;
    fs::create_directories(plan.log_dir, ec);
    if (ec) throw ProfileError("cannot create the log directory " + plan.log_dir + ": " + ec.message());
  }
  for (auto& [spec, argv] : plan.processes) {
    Managed m;
    m.spec = spec;
    m.argv = argv;
    managed_.push_back(std::move(m));
  }
  char host[256] = {0};
  gethostname(host, sizeof(host) - 1);
  host_ = host;
  host_label_ = options_.host_name.empty() ? host_ : options_.host_name;
  bus_ = std::make_unique<runtime::LcmBus>(options_.lcm_url, runtime::LcmBusOptions{channel(kHeartbeatChannel)});
  node_ = std::make_unique<SupervisorNode>(*this, *bus_);
}

Supervisor::~Supervisor() {
  shutting_down_ = true;
  shutdown();
}

void Supervisor::say(const std::string& line) const {
  std::cout << "[bricklayer " << format_seconds(since_start(Clock::now())) << "s] " << line << std::endl;
}

double Supervisor::since_start(Clock::time_point t) const { return std::chrono::duration<double>(t - t0_).count(); }

bool Supervisor::ready(const Managed& m) const {
  if (m.state == State::kUp) return true;
  if (m.state == State::kExited) return true;  // a one-shot that finished as its policy allows
  return m.spec.heartbeat.empty() && m.proc.started() && (m.state == State::kStarting);
}

// The start order moves past a module once it is up, or once it has failed to come up: the rest of
// the exhibit runs while it is retried.
bool Supervisor::settled(const Managed& m) const {
  return ready(m) || m.start_failed || m.state == State::kFailed || m.state == State::kClosed ||
         (m.spec.heartbeat.empty() && m.state != State::kPending);
}

bool Supervisor::bus_heard(Clock::time_point now) const { return now - last_self_heard_ < kDeafAfter; }

void Supervisor::start(Managed& m) {
  SpawnOptions opts;
  opts.cwd = options_.root;
  opts.env = m.spec.env;
  opts.env.push_back("LCM_DEFAULT_URL=" + options_.lcm_url);
  opts.env.push_back("BRICKLAYER_RESTARTS=" + std::to_string(m.restarts));
  try {
    m.proc = Process::spawn(m.argv, opts);
  } catch (const std::exception& e) {
    m.last_exit = std::string("cannot start: ") + e.what();
    say(m.spec.name + " " + m.last_exit + "; retrying in 1.0 s");
    m.start_failed = true;
    m.state = State::kWaitingRestart;
    m.restart_at = Clock::now() + std::chrono::seconds(1);
    return;
  }
  m.started = Clock::now();
  m.has_beat = false;
  m.state = m.spec.heartbeat.empty() ? State::kUp : State::kStarting;
  std::string cmd;
  for (const auto& a : m.argv) cmd += " " + a;
  say((m.restarts ? "restarting " : "starting ") + m.spec.name + " (pid " + std::to_string(m.proc.pid()) +
      (m.restarts ? ", restart #" + std::to_string(m.restarts) : "") + "):" + cmd);
}

void Supervisor::HandleHeartbeat(const heartbeat_t& hb) {
  const auto now = Clock::now();
  if (hb.module == "launcher" && hb.pid == static_cast<int32_t>(::getpid()) && hb.instance == host_ + ":" + std::to_string(hb.pid)) {
    last_self_heard_ = now;
    return;
  }
  for (auto& m : managed_) {
    if (m.spec.heartbeat.empty() || m.spec.heartbeat != hb.module || !m.proc.started() || m.proc.pid() != hb.pid)
      continue;
    if (m.state != State::kStarting && m.state != State::kUp) continue;
    // Another host's module with the same name and, by chance, the same pid is not ours.
    if (!hb.instance.empty() && hb.instance != host_ + ":" + std::to_string(hb.pid)) continue;
    m.last_beat = now;
    m.last = hb;
    m.has_beat = true;
    if (m.state == State::kStarting) {
      m.state = State::kUp;
      m.start_failed = false;
      say(m.spec.name + " up (pid " + std::to_string(hb.pid) + ", first heartbeat " +
          format_seconds(std::chrono::duration<double>(now - m.started).count()) + " s after start" +
          (m.restarts ? ", restarts " + std::to_string(hb.restarts) : "") + ")");
    }
  }
}

void Supervisor::HandleCommand(const command_t& c) {
  if (c.command != command_t::RESTART_MODULE) return;
  const auto slash = c.argument.find('/');
  const std::string host = slash == std::string::npos ? "" : c.argument.substr(0, slash);
  const std::string name = slash == std::string::npos ? c.argument : c.argument.substr(slash + 1);
  if (host != host_label_) return;  // another machine's launcher answers it
  for (auto& m : managed_) {
    if (m.spec.name != name) continue;
    if (m.state == State::kClosed || m.closing) {
      say("restart of " + name + " asked for while the exhibit is closed (" + profile_.opening_hours.closed_until(local_now()) +
          "): it starts at opening");
      return;
    }
    if (m.state == State::kWaitingRestart || m.state == State::kFailed || m.state == State::kExited) {
      // Not running (in its backoff, or given up by its policy): the operator's word starts it now.
      say("starting " + name + " now, as the operator asked");
      m.state = State::kWaitingRestart;
      m.restart_at = Clock::now();
      return;
    }
    if (m.state != State::kStarting && m.state != State::kUp) {
      say("restart of " + name + " asked for before it was first started: it starts in its turn");
      return;
    }
    // SIGTERM, so the module stops cleanly (a logger closes its file); the reap restarts it whatever its
    // restart policy, at once and without counting a quick failure.
    say("restarting " + name + " (pid " + std::to_string(m.proc.pid()) + ") as the operator asked");
    m.restart_requested = true;
    m.proc.signal(SIGTERM);
    return;
  }
  ++unknown_commands_;
  say("restart asked for a module this host does not run: \"" + name + "\" (counted)");
}

void Supervisor::HandleHostState(const host_state_t& hs) {
  if (hs.host == host_label_ && hs.launcher_pid == static_cast<int32_t>(::getpid())) return;  // our own
  const bool stopped = hs.num_modules > 0 && std::all_of(hs.modules.begin(), hs.modules.end(), [](const module_state_t& m) {
    return m.state == module_state_t::STATE_STOPPED;
  });
  auto [it, added] = peers_.try_emplace(hs.host);
  if (added) say("host " + hs.host + " (profile " + hs.profile + ") is on the bus: " + hs.status);
  else if (now_silent_.count(hs.host)) say("host " + hs.host + " is heard again: " + hs.status);
  now_silent_.erase(hs.host);
  it->second.last_seen = Clock::now();
  it->second.stopped = stopped;
}

// "no host state from projector-host for 7 s", for every other host missed; "" when none.
std::string Supervisor::silent_peers(Clock::time_point now) const {
  std::string out;
  for (const auto& [host, peer] : peers_) {
    if (peer.stopped || now - peer.last_seen < kPeerSilentAfter) continue;
    out += (out.empty() ? "" : "; ") + std::string("no host state from ") + host + " for " +
           std::to_string(static_cast<int>(std::chrono::duration<double>(now - peer.last_seen).count())) + " s";
  }
  return out;
}

void Supervisor::ended(Managed& m, Clock::time_point now) {
  // The counters of the process that ended stay in the module's totals.
  if (m.has_beat) {
    m.before.received += m.last.received;
    m.before.published += m.last.published;
    m.before.dropped += m.last.dropped;
    m.before.errors += m.last.errors;
  }
  const bool came_up = m.has_beat || (m.spec.heartbeat.empty() && m.state == State::kUp);
  m.has_beat = false;
  m.last = heartbeat_t{};
  ExitStatus st = m.proc.exit_status().value_or(ExitStatus{});
  m.last_exit = st.describe();
  bool up_long = m.state == State::kUp && now - m.started > std::chrono::seconds(10);
  const bool asked = m.restart_requested;
  m.restart_requested = false;
  if (m.closing) {
    m.closing = false;
    m.state = State::kClosed;
    say(m.spec.name + " (pid " + std::to_string(m.proc.pid()) + ") stopped for the closing time: " + m.last_exit);
    return;
  }
  bool restart = asked || m.spec.restart == RestartPolicy::kAlways ||
                 (m.spec.restart == RestartPolicy::kOnFailure && !st.clean());
  if (!came_up && !m.spec.heartbeat.empty()) m.start_failed = true;
  if (!restart) {
    m.state = st.clean() ? State::kExited : State::kFailed;
    say(m.spec.name + " (pid " + std::to_string(m.proc.pid()) + ") ended: " + m.last_exit + "; restart policy " +
        to_string(m.spec.restart) + ", not restarting" + (st.clean() ? "" : ": it stays down"));
    return;
  }
  if (asked) {
    say(m.spec.name + " (pid " + std::to_string(m.proc.pid()) + ") stopped for the operator's restart: " + m.last_exit +
        "; starting it again");
    m.state = State::kWaitingRestart;
    m.restart_at = now;
    return;
  }
  m.quick_failures = up_long ? 0 : m.quick_failures + 1;
  // Capped backoff, never giving up: an exhibit's camera may be plugged in an hour later.
  double delay = std::min(m.spec.backoff_max_s, 0.1 * std::pow(2.0, std::min(20, std::max(0, m.quick_failures - 1))));
  say(m.spec.name + " (pid " + std::to_string(m.proc.pid()) + ") " + (came_up ? "died" : "died before it came up") +
      ": " + m.last_exit + "; restarting in " + format_seconds(delay) + " s" +
      (m.quick_failures > 1 ? " (" + std::to_string(m.quick_failures) + " quick failures in a row)" : ""));
  m.state = State::kWaitingRestart;
  m.restart_at = now + seconds(delay);
}

LocalTime Supervisor::local_now() const {
  return options_.local_clock ? options_.local_clock() : local_time_of(std::time(nullptr));
}

// Opening hours and the nightly restart, on the local clock. Level-triggered: whatever the clock says
// now is what the modules do, so a launcher started at night keeps them stopped until opening.
void Supervisor::follow_schedule(Clock::time_point now) {
  const LocalTime local = local_now();
  const bool open = profile_.opening_hours.open_at(local);
  if (open != open_ || !schedule_started_) {
    int closing = 0;
    for (const auto& m : managed_) closing += closes(m) ? 1 : 0;
    if (!open && !schedule_started_)
      say("closed now (opening hours " + profile_.opening_hours.text() + ", local time " + clock_text(local.second) + "): " +
          std::to_string(closing) + " of " + std::to_string(managed_.size()) + " processes start at opening; " +
          profile_.opening_hours.closed_until(local));
    else if (!open)
      say("closing time (opening hours " + profile_.opening_hours.text() + ", local time " + clock_text(local.second) +
          "): stopping " + std::to_string(closing) + " of " + std::to_string(managed_.size()) + " processes; " +
          profile_.opening_hours.closed_until(local));
    else if (schedule_started_)
      say("opening time (opening hours " + profile_.opening_hours.text() + ", local time " + clock_text(local.second) +
          "): starting the modules");
    if (open && schedule_started_) all_up_announced_ = false;  // say "all up" (and where to look) again each opening
    open_ = open;
  }
  for (size_t i = 0; i < managed_.size(); ++i) {
    Managed& m = managed_[i];
    if (!closes(m)) continue;
    if (open) {
      if (m.state != State::kClosed) continue;
      // In start order again: the start loop goes on from the first module it finds waiting.
      m.state = State::kPending;
      m.start_failed = false;
      m.quick_failures = 0;
      next_to_start_ = std::min(next_to_start_, i);
      continue;
    }
    switch (m.state) {
      case State::kStarting:
      case State::kUp:
        if (!m.closing) {
          m.closing = true;
          m.close_deadline = now + seconds(profile_.stop_timeout_s);
          m.proc.signal(SIGTERM);
        } else if (now > m.close_deadline && m.proc.running()) {
          say(m.spec.name + " ignored SIGTERM for " + format_seconds(profile_.stop_timeout_s) + " s at closing time: SIGKILL");
          m.proc.signal(SIGKILL);
          m.close_deadline = now + std::chrono::hours(1);  // one kill; the reap takes it
        }
        break;
      case State::kWaitingRestart:
      case State::kFailed:
      case State::kExited:
        m.state = State::kClosed;  // a one-shot or a failed module starts afresh at opening
        break;
      case State::kPending:  // the start loop marks it closed in its turn
      case State::kStopped:
      case State::kClosed: break;
    }
  }
  // Once a day every running process starts afresh, cleanly (SIGTERM; the reap starts it again at once).
  if (profile_.nightly_restart >= 0 && schedule_started_ && passes(prev_local_, local, profile_.nightly_restart)) {
    int n = 0;
    for (auto& m : managed_) {
      if ((m.state != State::kStarting && m.state != State::kUp) || m.closing || !m.proc.running()) continue;
      m.restart_requested = true;
      m.proc.signal(SIGTERM);
      ++n;
    }
    ++nightly_restarts_;
    say("nightly restart (" + clock_text(profile_.nightly_restart) + "): restarting " + std::to_string(n) +
        " running processes" + (open ? "" : " (closed: the others start afresh at opening)"));
  }
  prev_local_ = local;
  schedule_started_ = true;
}

void Supervisor::tick() {
  if (shutting_down_) return;
  auto now = Clock::now();
  // 0. Opening hours and the nightly restart.
  follow_schedule(now);
  // 1. Reap: a dead module is restarted by its policy, after a backoff when it keeps dying quickly.
  for (auto& m : managed_) {
    if ((m.state != State::kStarting && m.state != State::kUp) || m.proc.running()) continue;
    ended(m, now);
  }
  // 2. Restarts that are due.
  for (auto& m : managed_) {
    if (m.state == State::kWaitingRestart && now >= m.restart_at) {
      ++m.restarts;
      start(m);
    }
  }
  // 3. Readiness and liveness deadlines, only while the bus carries the launcher's own heartbeat: on a
  //    deaf bus every module is silent, and killing them would only turn a network fault into restarts.
  const bool heard = bus_heard(now);
  if (!heard) {
    if (!bus_was_deaf_ && now - t0_ > kDeafAfter)
      say("the launcher hears nothing on the bus (not even itself): no module is judged by its silence until it does" +
          (bus_->problem().empty() ? std::string() : " (" + bus_->problem() + ")"));
    bus_was_deaf_ = bus_was_deaf_ || now - t0_ > kDeafAfter;
    repair_route(now);
  } else if (bus_was_deaf_) {
    bus_was_deaf_ = false;
    say("the bus carries the launcher's heartbeat again: watching the modules' heartbeats from now");
    for (auto& m : managed_) {
      if (m.state == State::kUp) m.last_beat = now;
      if (m.state == State::kStarting) m.started = now;
    }
  }
  for (auto& m : managed_) {
    if (!heard) break;
    if (m.closing) continue;  // stopping for the closing time: its own deadline
    if (m.state == State::kStarting && !m.spec.heartbeat.empty() && now - m.started > seconds(m.spec.ready_timeout_s)) {
      say(m.spec.name + " (pid " + std::to_string(m.proc.pid()) + ") sent no heartbeat on " + channel(kHeartbeatChannel) +
          " within " + format_seconds(m.spec.ready_timeout_s) + " s of starting: killing it (see its output above)");
      m.start_failed = true;
      m.proc.signal(SIGKILL);
      m.started = now;  // one kill per timeout; the reap restarts it
    } else if (m.state == State::kUp && m.has_beat && now - m.last_beat > seconds(m.spec.heartbeat_timeout_s)) {
      log::warn(m.spec.name, " (pid ", m.proc.pid(), ") silent for ", m.spec.heartbeat_timeout_s, " s; killing it");
      say(m.spec.name + " silent for " + format_seconds(m.spec.heartbeat_timeout_s) + " s: killing it");
      m.proc.signal(SIGKILL);
      m.last_beat = now;
    }
  }
  // 4. Start in order: the next module once everything before it is up, or has failed to come up.
  //    Outside the opening hours a module that closes is marked closed instead; a running one is skipped
  //    (the order is gone through again from the first module that opens).
  while (next_to_start_ < managed_.size() && (next_to_start_ == 0 || settled(managed_[next_to_start_ - 1]))) {
    Managed& m = managed_[next_to_start_];
    if (m.state == State::kPending) {
      if (!open_ && closes(m))
        m.state = State::kClosed;
      else
        start(m);
    }
    ++next_to_start_;
  }
  // 5. Everything up: say where to look. Anything down: say exactly what, each time that changes.
  const bool any_closed = std::any_of(managed_.begin(), managed_.end(),
                                      [](const Managed& m) { return m.state == State::kClosed || m.closing; });
  if (next_to_start_ == managed_.size() && !any_closed) {
    const std::string down = down_summary();
    const bool all_started_once = std::all_of(managed_.begin(), managed_.end(), [this](const Managed& m) { return settled(m); });
    if (down.empty() && !all_up_announced_) {
      all_up_announced_ = true;
      announced_down_.clear();
      say("all " + std::to_string(managed_.size()) + " processes of profile " + profile_.name + " are up");
      for (const auto& note : profile_.notes) say("  " + note);
      if (!log_file_.empty()) say("  bus log: " + log_file_ + " (replay: bricklayer-replay LOG --check)");
      say(options_.duration_s > 0 ? "  stopping by itself after " + format_seconds(options_.duration_s) + " s (Ctrl-C stops earlier)"
                                  : "  stop with Ctrl-C");
    } else if (down.empty() && !announced_down_.empty()) {
      announced_down_.clear();
      say("all " + std::to_string(managed_.size()) + " processes of profile " + profile_.name + " are up again");
    } else if (!down.empty() && down != announced_down_ && all_started_once) {
      announced_down_ = down;
      say(std::to_string(host_state().modules_up) + " of " + std::to_string(managed_.size()) + " processes of profile " + profile_.name + " are up; down: " + down);
    }
  }
  // 6. Other hosts that went silent are said once (the status says it for as long as it lasts).
  for (const auto& [host, peer] : peers_) {
    if (peer.stopped || now - peer.last_seen < kPeerSilentAfter || now_silent_.count(host)) continue;
    now_silent_.insert(host);
    say("no host state from " + host + " for " + format_seconds(static_cast<double>(kPeerSilentAfter.count())) +
        " s (the other machine off, or the link between us down?)");
  }
  // 7. Duration.
  if (options_.duration_s > 0 && since_start(now) >= options_.duration_s) {
    say("duration of " + format_seconds(options_.duration_s) + " s reached; stopping");
    runtime::Node::request_stop();
  }
}

// "camera (restarting: exit code 1), vision (starting)": the modules not up, in start order; "" when
// none. Words only (no counts or times), so the line changes when what is down changes.
std::string Supervisor::down_summary() const {
  std::string out;
  for (const auto& m : managed_) {
    std::string what;
    switch (m.state) {
      case State::kUp:
      case State::kExited:
      case State::kStopped:
      case State::kClosed: continue;
      case State::kPending: what = "waiting to start"; break;
      case State::kStarting:
        if (ready(m) || m.closing) continue;
        what = m.start_failed ? "restarting: " + m.last_exit : "starting";
        break;
      case State::kWaitingRestart: what = "restarting: " + m.last_exit; break;
      case State::kFailed: what = "failed: " + m.last_exit; break;
    }
    out += (out.empty() ? "" : ", ") + m.spec.name + " (" + what + ")";
  }
  return out;
}

void Supervisor::repair_route(Clock::time_point now) {
  if (options_.multicast_route_dev.empty() || now < next_route_repair_) return;
  next_route_repair_ = now + std::chrono::seconds(2);
  const std::string ip = find_program("ip", "", {"/usr/sbin", "/sbin", "/usr/bin", "/bin"});
  if (ip.empty()) {
    node_->warn("multicast route", "cannot put the multicast route back: no 'ip' program");
    return;
  }
  Process p = Process::spawn({ip, "route", "replace", "224.0.0.0/4", "dev", options_.multicast_route_dev},
                             SpawnOptions{"", {}, "/dev/null", "/dev/null", false, /*keep_ambient_capabilities=*/true});
  auto st = p.wait_for(std::chrono::seconds(2));
  if (st && st->clean()) {
    say("put the multicast route back: ip route replace 224.0.0.0/4 dev " + options_.multicast_route_dev);
  } else {
    // Usually the interface is still down; the warning says it once per 10 s with a count.
    node_->warn("multicast route", "ip route replace 224.0.0.0/4 dev " + options_.multicast_route_dev + " failed (" +
                                       (st ? st->describe() : std::string("timed out")) +
                                       "; interface still down, or no CAP_NET_ADMIN); trying again");
  }
}

Supervisor::Totals Supervisor::totals(const Managed& m) const {
  Totals t = m.before;
  if (m.has_beat) {
    t.received += m.last.received;
    t.published += m.last.published;
    t.dropped += m.last.dropped;
    t.errors += m.last.errors;
  }
  return t;
}

std::string Supervisor::status_of(const Managed& m, Clock::time_point now) const {
  auto ago = [&](Clock::time_point t) { return format_seconds(std::chrono::duration<double>(now - t).count()); };
  switch (m.state) {
    case State::kPending: return "waiting for the modules before it to come up";
    case State::kStarting:
      if (m.spec.heartbeat.empty()) return "running (no heartbeat)";
      return "started " + ago(m.started) + " s ago, no heartbeat yet";
    case State::kUp:
      if (m.closing) return "stopping for the closing time";
      return m.has_beat ? m.last.status : "running (no heartbeat)";
    case State::kWaitingRestart:
      return "restarting in " + format_seconds(std::max(0.0, std::chrono::duration<double>(m.restart_at - now).count())) +
             " s after " + m.last_exit;
    case State::kFailed: return "down for good (restart policy " + to_string(m.spec.restart) + "): " + m.last_exit;
    case State::kExited: return "finished: " + m.last_exit;
    case State::kStopped: return "stopped: " + m.last_exit;
    case State::kClosed: return profile_.opening_hours.closed_until(local_now());
  }
  return "?";
}

host_state_t Supervisor::host_state() const {
  const auto now = Clock::now();
  host_state_t hs{};
  hs.utime = bus_->now_utime();
  hs.host = host_label_;
  hs.launcher_pid = static_cast<int32_t>(::getpid());
  hs.profile = profile_.name;
  hs.uptime_us = std::chrono::duration_cast<std::chrono::microseconds>(now - t0_).count();
  for (const auto& m : managed_) {
    module_state_t s{};
    s.name = m.spec.name;
    switch (m.state) {
      case State::kPending: s.state = module_state_t::STATE_WAITING; break;
      case State::kStarting: s.state = ready(m) ? module_state_t::STATE_UP : module_state_t::STATE_STARTING; break;
      case State::kUp: s.state = module_state_t::STATE_UP; break;
      case State::kWaitingRestart: s.state = module_state_t::STATE_RESTARTING; break;
      case State::kFailed: s.state = module_state_t::STATE_FAILED; break;
      case State::kExited: s.state = module_state_t::STATE_EXITED; break;
      case State::kStopped: s.state = module_state_t::STATE_STOPPED; break;
      // Not started yet, as WAITING says, and starting by itself at opening (restart_in_us). Not STOPPED:
      // that is a host shut down on purpose, which the other host stops missing.
      case State::kClosed: s.state = module_state_t::STATE_WAITING; break;
    }
    const bool running = (m.state == State::kStarting || m.state == State::kUp) && m.proc.started();
    s.pid = running ? m.proc.pid() : 0;
    s.restarts = m.restarts;
    s.uptime_us = running ? std::chrono::duration_cast<std::chrono::microseconds>(now - m.started).count() : 0;
    s.restart_in_us = m.state == State::kWaitingRestart
                          ? std::max<int64_t>(0, std::chrono::duration_cast<std::chrono::microseconds>(m.restart_at - now).count())
                          : 0;
    if (m.state == State::kClosed)
      s.restart_in_us = static_cast<int64_t>(static_cast<double>(profile_.opening_hours.seconds_until_open(local_now())) * 1e6 /
                                             std::max(1e-6, options_.local_clock_speed));
    const Totals t = totals(m);
    s.received = t.received;
    s.published = t.published;
    s.dropped = t.dropped;
    s.errors = t.errors;
    s.status = status_of(m, now);
    s.last_exit = m.last_exit;
    if (s.state == module_state_t::STATE_UP || s.state == module_state_t::STATE_EXITED) ++hs.modules_up;
    hs.modules.push_back(std::move(s));
  }
  hs.num_modules = static_cast<int32_t>(hs.modules.size());
  const std::string down = down_summary();
  const std::string silent = silent_peers(now);
  hs.status = down.empty() ? "" : "down: " + down;
  if (!open_) {
    // "closed until 09:30": what the status page shows for this host all night.
    const std::string closed = profile_.opening_hours.closed_until(local_now());
    hs.status = closed + (hs.status.empty() ? "" : "; " + hs.status);
  }
  if (!silent.empty()) hs.status += (hs.status.empty() ? "" : "; ") + silent;
  if (hs.status.empty()) hs.status = "ok";
  return hs;
}

void Supervisor::before_heartbeat() {
  const host_state_t hs = host_state();
  int closed = 0;
  for (const auto& m : managed_) closed += m.state == State::kClosed ? 1 : 0;
  node_->set_value("modules_up", hs.modules_up);
  node_->set_value("modules_down", hs.num_modules - hs.modules_up - closed);
  node_->set_value("modules_closed", closed);
  node_->set_value("nightly_restarts", nightly_restarts_);
  int restarts = 0;
  for (const auto& m : managed_) restarts += m.restarts;
  node_->set_value("restarts_total", restarts);
  node_->set_value("restart_requests_unknown", static_cast<double>(unknown_commands_));
  node_->set_status(hs.status);
  node_->publish_report(channel(kHostStateChannel), hs);
}

int Supervisor::run() {
  t0_ = Clock::now();
  last_self_heard_ = t0_;  // grace until the first heartbeat has had time to come back
  if (!profile_.description.empty()) say("profile " + profile_.name + ": " + profile_.description);
  say("LCM bus: " + options_.lcm_url);
  if (!profile_.opening_hours.always_open()) say("opening hours: " + profile_.opening_hours.text() + " (local time)");
  if (profile_.nightly_restart >= 0) say("nightly restart of every running process at " + clock_text(profile_.nightly_restart) + " (local time)");
  runtime::Node::install_signal_handlers();
  if (!runtime::Node::stop_requested()) node_->run();
  shutting_down_ = true;
  const std::string down = down_summary();
  shutdown();
  print_summary();
  if (!down.empty()) say("down at the stop: " + down);
  return down.empty() ? 0 : 1;
}

void Supervisor::shutdown() {
  auto deadline = std::chrono::milliseconds(static_cast<int64_t>(profile_.stop_timeout_s * 1000));
  // SIGTERM to everything at once (reverse start order), one shared deadline, then SIGKILL; the
  // logger (first started) is stopped last so it records the others' final heartbeats.
  std::vector<Managed*> order;
  for (auto it = managed_.rbegin(); it != managed_.rend(); ++it)
    if (it->proc.running()) order.push_back(&*it);
  // Modules closed for the night are stopped too: the last host state says every module stopped.
  bool had_closed = false;
  for (auto& m : managed_) {
    if (m.state != State::kClosed) continue;
    m.state = State::kStopped;
    had_closed = true;
  }
  if (order.empty()) {
    if (had_closed) node_->publish_report(channel(kHostStateChannel), host_state());
    return;
  }
  auto is_logger = [this](const Managed* m) { return profile_.logger && m == &managed_.front(); };
  for (Managed* m : order)
    if (!is_logger(m)) m->proc.signal(SIGTERM);
  // Keep listening while they stop, so the summary has every module's final heartbeat.
  auto until = Clock::now() + deadline;
  auto any_running = [&] {
    return std::any_of(order.begin(), order.end(), [&](Managed* m) { return !is_logger(m) && m->proc.running(); });
  };
  while (any_running() && Clock::now() < until) node_->step(10);
  for (Managed* m : order) {
    if (is_logger(m) || !m->proc.running()) continue;
    say(m->spec.name + " ignored SIGTERM for " + format_seconds(profile_.stop_timeout_s) + " s: SIGKILL");
    m->proc.signal(SIGKILL);
    m->proc.wait_for(std::chrono::seconds(5));
  }
  for (int i = 0; i < 30; ++i) node_->step(10);
  for (Managed* m : order) {
    if (is_logger(m)) continue;
    if (auto st = m->proc.exit_status()) m->last_exit = st->describe();
    m->state = State::kStopped;
  }
  // The modules' final state, for an observer that outlives this launcher.
  node_->publish_report(channel(kHostStateChannel), host_state());
  // Let the logger write the last heartbeats before it goes.
  for (Managed* m : order) {
    if (!is_logger(m)) continue;
    ExitStatus st = m->proc.stop(deadline);
    m->last_exit = st.describe();
    m->state = State::kStopped;
  }
}

void Supervisor::print_summary() const {
  std::ostringstream out;
  out << "summary of profile " << profile_.name << " after " << format_seconds(since_start(Clock::now())) << " s"
      << " (counters of every process of a module, summed across its restarts):\n";
  char line[512];
  std::snprintf(line, sizeof(line), "  %-12s %8s %10s %10s %8s %8s  %s\n", "module", "restarts", "received",
                "published", "dropped", "errors", "last status");
  out << line;
  for (const auto& m : managed_) {
    const Totals t = totals(m);
    const bool any = m.has_beat || t.received || t.published || t.dropped || t.errors || m.restarts;
    const std::string status = m.has_beat ? m.last.status
                               : m.state == State::kPending ? "never started"
                               : m.last_exit.empty()        ? "(no heartbeat)"
                                                            : "(no heartbeat; last: " + m.last_exit + ")";
    if (any && !m.spec.heartbeat.empty()) {
      std::snprintf(line, sizeof(line), "  %-12s %8d %10lld %10lld %8lld %8lld  %s\n", m.spec.name.c_str(), m.restarts,
                    static_cast<long long>(t.received), static_cast<long long>(t.published),
                    static_cast<long long>(t.dropped), static_cast<long long>(t.errors), status.c_str());
    } else {
      std::snprintf(line, sizeof(line), "  %-12s %8d %10s %10s %8s %8s  %s\n", m.spec.name.c_str(), m.restarts, "-", "-",
                    "-", "-", status.c_str());
    }
    out << line;
  }
  if (!log_file_.empty()) {
    std::error_code ec;
    auto size = fs::file_size(log_file_, ec);
    out << "  bus log: " << log_file_;
    if (!ec) out << " (" << format_seconds(static_cast<double>(size) / 1e6) << " MB)";
    out << "\n";
  }
  std::cout << out.str() << std::flush;
}

}  // namespace bricklayer::launcher
