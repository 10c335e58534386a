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
  module_ = std::make_unique<Module>("launcher", options_.lcm_url);
  module_->subscribe<heartbeat_t>(channel(kHeartbeatChannel), [this](const heartbeat_t& hb) { HandleHeartbeat(hb); });
}

Supervisor::~Supervisor() { shutdown(); }

void Supervisor::say(const std::string& line) const {
  std::cout << "[bricklayer " << format_seconds(since_start(Clock::now())) << "s] " << line << std::endl;
}

double Supervisor::since_start(Clock::time_point t) const { return std::chrono::duration<double>(t - t0_).count(); }

bool Supervisor::ready(const Managed& m) const {
  if (m.state == State::kUp) return true;
  if (m.state == State::kExited) return true;  // a one-shot that finished as its policy allows
  return m.spec.heartbeat.empty() && m.proc.started() && m.state != State::kPending;
}

void Supervisor::start(Managed& m) {
  SpawnOptions opts;
  opts.cwd = options_.root;
  opts.env = m.spec.env;
  opts.env.push_back("LCM_DEFAULT_URL=" + options_.lcm_url);
  opts.env.push_back("BRICKLAYER_RESTARTS=" + std::to_string(m.restarts));
  try {
    m.proc = Process::spawn(m.argv, opts);
  } catch (const std::exception& e) {
    log::error("cannot start ", m.spec.name, ": ", e.what());
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
  for (auto& m : managed_) {
    if (m.spec.heartbeat.empty() || m.spec.heartbeat != hb.module || !m.proc.started() || m.proc.pid() != hb.pid)
      continue;
    if (m.state != State::kStarting && m.state != State::kUp) continue;
    // Another host's module with the same name and, by chance, the same pid is not ours.
    if (!hb.instance.empty() && hb.instance != host_ + ":" + std::to_string(hb.pid)) continue;
    auto now = Clock::now();
    m.last_beat = now;
    m.last = hb;
    m.has_beat = true;
    if (m.state == State::kStarting) {
      m.state = State::kUp;
      say(m.spec.name + " up (pid " + std::to_string(hb.pid) + ", first heartbeat " +
          format_seconds(std::chrono::duration<double>(now - m.started).count()) + " s after start" +
          (m.restarts ? ", restarts " + std::to_string(hb.restarts) : "") + ")");
    }
  }
}

void Supervisor::tick() {
  auto now = Clock::now();
  // 1. Reap: a dead module is restarted by its policy, after a backoff when it keeps dying quickly.
  for (auto& m : managed_) {
    if ((m.state != State::kStarting && m.state != State::kUp) || m.proc.running()) continue;
    ExitStatus st = m.proc.exit_status().value_or(ExitStatus{});
    m.last_exit = st.describe();
    bool up_long = m.state == State::kUp && now - m.started > std::chrono::seconds(10);
    bool restart = m.spec.restart == RestartPolicy::kAlways || (m.spec.restart == RestartPolicy::kOnFailure && !st.clean());
    if (!restart) {
      say(m.spec.name + " (pid " + std::to_string(m.proc.pid()) + ") ended: " + m.last_exit + "; restart policy " +
          to_string(m.spec.restart) + ", not restarting");
      m.state = State::kExited;
      if (!st.clean() && !all_up_announced_) {
        log::error(m.spec.name, " failed while the profile was starting (", m.last_exit, ")");
        fatal_ = true;
        Module::request_stop();
      }
      continue;
    }
    m.quick_failures = up_long ? 0 : m.quick_failures + 1;
    if (!all_up_announced_ && !m.has_beat && m.quick_failures >= 3) {
      log::error(m.spec.name, " exited ", m.quick_failures, " times before its first heartbeat (last: ", m.last_exit,
                 "); see its output above. Stopping.");
      say(m.spec.name + " keeps exiting before it comes up (" + m.last_exit + "): giving up");
      fatal_ = true;
      Module::request_stop();
      m.state = State::kExited;
      continue;
    }
    double delay = std::min(5.0, 0.1 * std::pow(2.0, std::max(0, m.quick_failures - 1)));
    log::warn(m.spec.name, " (pid ", m.proc.pid(), ") died: ", m.last_exit, "; restarting in ", format_seconds(delay), " s");
    say(m.spec.name + " (pid " + std::to_string(m.proc.pid()) + ") died: " + m.last_exit + "; restarting in " +
        format_seconds(delay) + " s");
    m.state = State::kWaitingRestart;
    m.restart_at = now + std::chrono::microseconds(static_cast<int64_t>(delay * 1e6));
  }
  // 2. Restarts that are due.
  for (auto& m : managed_) {
    if (m.state == State::kWaitingRestart && now >= m.restart_at) {
      ++m.restarts;
      start(m);
    }
  }
  // 3. Readiness and liveness deadlines.
  for (auto& m : managed_) {
    if (m.state == State::kStarting &&
        now - m.started > std::chrono::microseconds(static_cast<int64_t>(m.spec.ready_timeout_s * 1e6))) {
      if (!all_up_announced_) {
        log::error(m.spec.name, " (pid ", m.proc.pid(), ") sent no heartbeat on ", channel(kHeartbeatChannel),
                   " within ", m.spec.ready_timeout_s, " s of starting; see its output above. Stopping.");
        fatal_ = true;
        Module::request_stop();
        return;
      }
      log::warn(m.spec.name, " sent no heartbeat within ", m.spec.ready_timeout_s, " s; killing it");
      m.proc.signal(SIGKILL);
    } else if (m.state == State::kUp && m.has_beat &&
               now - m.last_beat > std::chrono::microseconds(static_cast<int64_t>(m.spec.heartbeat_timeout_s * 1e6))) {
      log::warn(m.spec.name, " (pid ", m.proc.pid(), ") silent for ", m.spec.heartbeat_timeout_s, " s; killing it");
      say(m.spec.name + " silent for " + format_seconds(m.spec.heartbeat_timeout_s) + " s: killing it");
      m.proc.signal(SIGKILL);
    }
  }
  // 4. Start in order: the next module only once everything before it is up.
  while (next_to_start_ < managed_.size() &&
         (next_to_start_ == 0 || ready(managed_[next_to_start_ - 1]))) {
    start(managed_[next_to_start_]);
    ++next_to_start_;
  }
  // 5. Everything up: say where to look.
  if (!all_up_announced_ && next_to_start_ == managed_.size() &&
      std::all_of(managed_.begin(), managed_.end(), [this](const Managed& m) { return ready(m); })) {
    all_up_announced_ = true;
    say("all " + std::to_string(managed_.size()) + " processes of profile " + profile_.name + " are up");
    for (const auto& note : profile_.notes) say("  " + note);
    if (!log_file_.empty()) say("  bus log: " + log_file_ + " (replay: bricklayer-replay LOG --check)");
    say(options_.duration_s > 0 ? "  stopping by itself after " + format_seconds(options_.duration_s) + " s (Ctrl-C stops earlier)"
                                : "  stop with Ctrl-C");
  }
  // 6. Duration.
  if (options_.duration_s > 0 && since_start(now) >= options_.duration_s) {
    say("duration of " + format_seconds(options_.duration_s) + " s reached; stopping");
    Module::request_stop();
  }
  module_->set_value("modules_up", static_cast<double>(std::count_if(
                                       managed_.begin(), managed_.end(), [](const Managed& m) { return m.state == State::kUp; })));
  int restarts = 0;
  for (const auto& m : managed_) restarts += m.restarts;
  module_->set_value("restarts_total", restarts);
}

int Supervisor::run() {
  t0_ = Clock::now();
  if (!profile_.description.empty()) say("profile " + profile_.name + ": " + profile_.description);
  say("LCM bus: " + options_.lcm_url);
  Module::install_signal_handlers();
  if (!Module::stop_requested()) module_->run([this] { tick(); }, 20);
  shutdown();
  print_summary();
  return fatal_ ? 1 : 0;
}

void Supervisor::shutdown() {
  auto deadline = std::chrono::milliseconds(static_cast<int64_t>(profile_.stop_timeout_s * 1000));
  // SIGTERM to everything at once (reverse start order), one shared deadline, then SIGKILL; the
  // logger (first started) is stopped last so it records the others' final heartbeats.
  std::vector<Managed*> order;
  for (auto it = managed_.rbegin(); it != managed_.rend(); ++it)
    if (it->proc.running()) order.push_back(&*it);
  if (order.empty()) return;
  auto is_logger = [this](const Managed* m) { return profile_.logger && m == &managed_.front(); };
  for (Managed* m : order)
    if (!is_logger(m)) m->proc.signal(SIGTERM);
  // Keep listening while they stop, so the summary has every module's final heartbeat.
  auto until = Clock::now() + deadline;
  auto any_running = [&] {
    return std::any_of(order.begin(), order.end(), [&](Managed* m) { return !is_logger(m) && m->proc.running(); });
  };
  while (any_running() && Clock::now() < until) module_->lcm().handleTimeout(10);
  for (Managed* m : order) {
    if (is_logger(m) || !m->proc.running()) continue;
    say(m->spec.name + " ignored SIGTERM for " + format_seconds(profile_.stop_timeout_s) + " s: SIGKILL");
    m->proc.signal(SIGKILL);
    m->proc.wait_for(std::chrono::seconds(5));
  }
  for (int i = 0; i < 30 && module_->lcm().handleTimeout(10) > 0; ++i) {
  }
  for (Managed* m : order) {
    if (is_logger(m)) continue;
    if (auto st = m->proc.exit_status()) m->last_exit = st->describe();
    m->state = State::kStopped;
  }
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
      << (fatal_ ? " (FAILED to start)" : "") << ":\n";
  char line[256];
  std::snprintf(line, sizeof(line), "  %-12s %8s %10s %10s %8s %8s  %s\n", "module", "restarts", "received",
                "published", "dropped", "errors", "last status");
  out << line;
  for (const auto& m : managed_) {
    if (m.has_beat) {
      std::snprintf(line, sizeof(line), "  %-12s %8d %10lld %10lld %8lld %8lld  %s\n", m.spec.name.c_str(), m.restarts,
                    static_cast<long long>(m.last.received), static_cast<long long>(m.last.published),
                    static_cast<long long>(m.last.dropped), static_cast<long long>(m.last.errors),
                    m.last.status.c_str());
    } else {
      std::snprintf(line, sizeof(line), "  %-12s %8d %10s %10s %8s %8s  %s\n", m.spec.name.c_str(), m.restarts, "-", "-",
                    "-", "-", m.state == State::kPending ? "never started" : "(no heartbeat)");
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
