// bricklayer-soak: the whole pipeline under load for a bounded time, with optional fault drills, and
// the soak and fault-drill checks. Run it inside a private network namespace (launch/soak does).
//
// Starts bricklayer-launch with a generated profile (vision, prediction, projection --headless,
// planner, bricklayer-logger) and plays camera frames onto BL_IMAGE itself: --frames distinct simcam renders
// of a --blocks pile (JPEG, as a camera would send them), cycled at --fps with increasing frame
// numbers. (The bricklayer-simcam process had not landed when this was written; the frames come from
// the same renderer.)
// Subscribes: BL_HEARTBEAT (every module), BL_PREDICTION, BL_TIMING. Publishes: BL_IMAGE.
// Checks, each a line of the summary; exit 1 when any fails:
//  - memory: VmRSS / VmHWM of every module process (pid from its heartbeat) at start and end; the
//    end RSS must stay under --max-rss-growth times the start RSS (+ 20 MB);
//  - heartbeats continuous (no gap > 2.5 s) for every module not being drilled; errors reported;
//    no queue growth: the age of each prediction (now - its camera frame's utime) is no larger at the
//    end of the run than at the start, and prediction's received - published - dropped stays bounded;
//  - log complete: every prediction_t seen on the bus is in the bricklayer-logger log (by
//    frame_number), and the log holds at least as many as the prediction processes' heartbeats say
//    they published; every camera frame this tool published is in it; the logger itself reports no
//    loss (queue full, kernel drops on its socket, frame-number gaps), runs as one process for the
//    whole run (it is not drilled) and its memory is bounded like the modules';
//  - --drill: kill -9 each module in turn; the launcher restarts it (new pid, restarts+1) within
//    --restart-limit s, the other modules keep their pids, and no gap between consecutive predictions
//    in the log is longer than the slowest restart + 1 s.
#include <lcm/lcm-cpp.hpp>
#include <signal.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <memory>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include <opencv2/imgcodecs.hpp>

#include "bricklayer/common/channels.h"
#include "bricklayer/common/flags.h"
#include "bricklayer/common/lcm_url.h"
#include "bricklayer/heartbeat_t.hpp"
#include "bricklayer/image_t.hpp"
#include "bricklayer/launcher/process.h"
#include "bricklayer/prediction_t.hpp"
#include "frames.h"
#include "bricklayer/timing_t.hpp"

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

namespace bricklayer {
namespace {

const std::vector<std::string> kModules = {"vision", "prediction", "projection", "planner"};  // drilled
const std::string kLogger = "logger";  // watched like a module, never drilled: the log must stay complete
std::vector<std::string> watched() {
  std::vector<std::string> all = kModules;
  all.push_back(kLogger);
  return all;
}
double value_of(const heartbeat_t& hb, const std::string& name) {
  for (size_t i = 0; i < hb.value_names.size() && i < hb.values.size(); ++i)
    if (hb.value_names[i] == name) return hb.values[i];
  return -1;
}

int64_t wall_us() {
  return std::chrono::duration_cast<std::chrono::microseconds>(std::chrono::system_clock::now().time_since_epoch())
      .count();
}
double since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

struct Memory {
  long rss_kb = -1, hwm_kb = -1;
};
Memory read_memory(int pid) {
  Memory m;
  std::ifstream in("/proc/" + std::to_string(pid) + "/status");
  std::string key;
  long value;
  std::string line;
  while (std::getline(in, line)) {
    std::istringstream s(line);
    s >> key >> value;
    if (key == "VmRSS:") m.rss_kb = value;
    if (key == "VmHWM:") m.hwm_kb = value;
  }
  return m;
}

struct ModuleWatch {
  int pid = 0;
  int32_t restarts = 0;
  double last_hb = -1;      // seconds since start
  double worst_gap = 0;     // longest heartbeat gap outside drills
  heartbeat_t first{}, last{};
  bool seen = false;
  Memory mem_start, mem_end;
  std::set<int> pids;
  int64_t backlog_mid = 0;
  int64_t retired_published = 0, retired_errors = 0, retired_dropped = 0, retired_received = 0;
};

class Soak {
 public:
  Soak(const Flags& f) : url_(resolve_lcm_url(f.get("lcm-url"))), lcm_(std::make_unique<lcm::LCM>(url_)) {
    duration_ = f.get_double("duration");
    fps_ = f.get_double("fps");
    blocks_ = static_cast<int>(f.get_int("blocks"));
    drill_ = f.get_bool("drill");
    restart_limit_ = f.get_double("restart-limit");
    max_rss_growth_ = f.get_double("max-rss-growth");
    bin_dir_ = f.get("bin-dir");
    root_ = f.get("root");
    out_dir_ = f.get("out-dir");
    frames_n_ = static_cast<int>(f.get_int("frames"));
    if (duration_ <= 0 || fps_ <= 0 || fps_ > 1000 || blocks_ < 1 || blocks_ > 2000 || frames_n_ < 1)
      throw FlagError("need --duration > 0, 0 < --fps <= 1000, 1 <= --blocks <= 2000, --frames >= 1");
    if (lcm_->getFileno() < 0) throw std::runtime_error("cannot open the LCM bus " + url_);
    lcm_->subscribe(channel(kHeartbeatChannel), &Soak::OnHeartbeat, this)->setQueueCapacity(10000);
    lcm_->subscribe(channel(kPredictionChannel), &Soak::OnPrediction, this)->setQueueCapacity(10000);
  }

  int run() {
    fs::create_directories(out_dir_);
    render_frames();
    const std::string profile = write_profile();
    launcher::SpawnOptions o;
    o.env = {"LCM_DEFAULT_URL=" + url_, "SDL_VIDEODRIVER=offscreen", "SDL_AUDIODRIVER=dummy"};
    o.stdout_path = out_dir_ + "/launch.log";
    o.merge_stderr = true;
    const int total = static_cast<int>(duration_) + 60;
    launch_ = launcher::Process::spawn({bin_dir_ + "/bricklayer-launch", "--root", root_, "--bin-dir", bin_dir_,
                                        profile, "--duration", std::to_string(total), "--log-level", "warn"}, o);
    // Wait for every module's heartbeat before the clock starts.
    t0_ = Clock::now();
    while (since(t0_) < 30) {
      lcm_->handleTimeout(20);
      bool all = true;
      for (const auto& m : watched()) all = all && watch_[m].seen;
      if (all) break;
      if (!launch_.running()) break;
    }
    for (const auto& m : watched())
      if (!watch_[m].seen) return fail_early("module " + m + " sent no heartbeat within 30 s (see " + out_dir_ + "/launch.log)");
    t0_ = Clock::now();
    for (auto& [name, w] : watch_) {
      w.mem_start = read_memory(w.pid);
      w.first = w.last;
      w.last_hb = 0;
    }
    play();
    // Final heartbeats, memory at the end, then stop everything and read the log.
    const double t_end = since(t0_);
    while (since(t0_) < t_end + 1.2) {
      publish_frame();
      lcm_->handleTimeout(static_cast<int>(1000 / fps_));
    }
    while (since(t0_) < t_end + 2.4) lcm_->handleTimeout(20);  // drain: no new frames, last answers and heartbeats
    for (auto& [name, w] : watch_) w.mem_end = read_memory(w.pid);
    sample_udp_drops();
    launch_.stop(std::chrono::seconds(15));
    return report();
  }

 private:
  void render_frames() {
    auto f = reliability::render_frames(blocks_, frames_n_);
    frames_ = std::move(f.jpeg);
    frame_size_ = f.size;
  }

  std::string write_profile() {
    const std::string path = out_dir_ + "/soak-profile.json";
    std::ofstream p(path);
    p << "{\n  \"description\": \"bricklayer-soak: the pipeline with frames from the soak tool\",\n"
      << "  \"stop_timeout_s\": 5,\n"
      << "  \"logger\": {\"file\": \"" << out_dir_ << "/soak-log\", \"rotate\": 0, \"split_mb\": 100000},\n"
      << "  \"modules\": [\n"
      << "    {\"name\": \"prediction\", \"command\": [\"bricklayer-prediction\"], \"restart\": \"always\"},\n"
      << "    {\"name\": \"projection\", \"command\": [\"bricklayer-projection\", \"--headless\"], \"restart\": \"always\"},\n"
      << "    {\"name\": \"planner\", \"command\": [\"bricklayer-planner\"], \"restart\": \"always\"},\n"
      << "    {\"name\": \"vision\", \"command\": [\"bricklayer-vision\"], \"restart\": \"always\"}\n"
      << "  ]\n}\n";
    return path;
  }

  void publish_frame() {
    const double t = since(t0_);
    while (next_frame_t_ <= t) {
      image_t m{};
      m.utime = wall_us();
      m.frame_number = frame_number_++;
      m.width = frame_size_.width;
      m.height = frame_size_.height;
      m.format = image_t::FORMAT_JPEG;
      m.source = "soak";
      m.data = frames_[static_cast<size_t>(m.frame_number) % frames_.size()];
      m.size = static_cast<int32_t>(m.data.size());
      if (lcm_->publish(channel(kImageChannel), &m) == 0) ++frames_published_;
      next_frame_t_ += 1.0 / fps_;
      if (next_frame_t_ < t - 1.0) next_frame_t_ = t;  // fell far behind: do not burst
    }
  }

  void play() {
    std::vector<std::pair<double, std::string>> drills;
    if (drill_) {
      for (size_t i = 0; i < kModules.size(); ++i)
        drills.push_back({duration_ * (i + 1) / (kModules.size() + 1), kModules[i]});
    }
    size_t next_drill = 0;
    bool mid_done = false;
    while (since(t0_) < duration_) {
      publish_frame();
      const double until = std::min(next_frame_t_, duration_);
      const int ms = std::max(0, static_cast<int>((until - since(t0_)) * 1000));
      lcm_->handleTimeout(std::max(1, ms));
      if (!mid_done && since(t0_) > duration_ / 2) {
        for (auto& [n, w] : watch_) w.backlog_mid = backlog(w.last);
        mid_done = true;
      }
      if (next_drill < drills.size() && since(t0_) >= drills[next_drill].first && !killing_) {
        const std::string& m = drills[next_drill].second;
        Drill d;
        d.module = m;
        d.old_pid = watch_[m].pid;
        d.old_restarts = watch_[m].restarts;
        d.at = since(t0_);
        ::kill(d.old_pid, SIGKILL);
        drill_log_.push_back(d);
        killing_ = true;
        ++next_drill;
      }
      if (killing_) {
        Drill& d = drill_log_.back();
        if (watch_[d.module].pid != d.old_pid) {
          d.restarted_after = watch_[d.module].last_hb - d.at;
          d.new_pid = watch_[d.module].pid;
          d.new_restarts = watch_[d.module].restarts;
          killing_ = false;
        } else if (since(t0_) - d.at > restart_limit_) {
          killing_ = false;  // failed: reported
        }
      }
      if (!launch_.running()) {
        std::cerr << "soak: bricklayer-launch exited early\n";
        break;
      }
    }
  }

  // Datagrams the kernel dropped because a receiver's buffer was full (/proc/net/udp "drops", every
  // socket on the bus port in this namespace): the only way a message can go missing on one host.
  void sample_udp_drops() {
    std::ifstream udp("/proc/net/udp");
    std::string line;
    std::getline(udp, line);
    const std::string port = url_.substr(url_.rfind(':') + 1, 4);
    char port_hex[8];
    std::snprintf(port_hex, sizeof port_hex, ":%04X", std::stoi(port));
    while (std::getline(udp, line)) {
      std::istringstream f(line);
      std::string sl, local;
      f >> sl >> local;
      if (local.size() < 5 || local.substr(local.size() - 5) != port_hex) continue;
      std::string field, last;
      while (f >> field) last = field;
      ++udp_sockets_;
      udp_drops_ += std::stol(last);
    }
  }

  static int64_t backlog(const heartbeat_t& h) { return h.received - h.published - h.dropped; }

  void OnHeartbeat(const lcm::ReceiveBuffer*, const std::string&, const heartbeat_t* hb) {
    auto it = watch_.find(hb->module);
    if (it == watch_.end()) {
      if (hb->module != kLogger && std::find(kModules.begin(), kModules.end(), hb->module) == kModules.end()) return;
      it = watch_.emplace(hb->module, ModuleWatch{}).first;
    }
    ModuleWatch& w = it->second;
    const double t = since(t0_);
    const bool drilled_now = killing_ && drill_log_.back().module == hb->module;
    if (w.seen && w.pid == hb->pid && w.last_hb >= 0 && !drilled_now) w.worst_gap = std::max(w.worst_gap, t - w.last_hb);
    if (w.seen && w.pid != hb->pid) {
      // A new process: accumulate the finished one's counters.
      w.retired_published += w.last.published;
      w.retired_errors += w.last.errors;
      w.retired_dropped += w.last.dropped;
      w.retired_received += w.last.received;
    }
    w.seen = true;
    w.pid = hb->pid;
    w.pids.insert(hb->pid);
    w.restarts = hb->restarts;
    w.last = *hb;
    w.last_hb = t;
  }

  void OnPrediction(const lcm::ReceiveBuffer*, const std::string&, const prediction_t* p) {
    seen_predictions_.insert(p->frame_number);
    if (p->frame_number < frame_number_) ages_.push_back({since(t0_), (wall_us() - p->utime) / 1000.0});
  }

  int fail_early(const std::string& why) {
    std::cout << "SOAK FAILED: " << why << "\n";
    launch_.stop(std::chrono::seconds(10));
    return 1;
  }

  struct Drill {
    std::string module;
    int old_pid = 0, new_pid = 0;
    int32_t old_restarts = 0, new_restarts = 0;
    double at = 0, restarted_after = -1;
  };

  int report();

  std::string url_;
  std::unique_ptr<lcm::LCM> lcm_;
  double duration_, fps_, restart_limit_, max_rss_growth_;
  int blocks_, frames_n_;
  bool drill_;
  std::string bin_dir_, root_, out_dir_;
  std::vector<std::vector<uint8_t>> frames_;
  cv::Size frame_size_;
  launcher::Process launch_;
  Clock::time_point t0_;
  double next_frame_t_ = 0;
  int64_t frame_number_ = 0;
  int64_t frames_published_ = 0;  // publish calls LCM accepted (frame numbers 0 .. frame_number_-1)
  std::map<std::string, ModuleWatch> watch_;
  std::vector<Drill> drill_log_;
  bool killing_ = false;
  std::set<int64_t> seen_predictions_;
  std::vector<std::pair<double, double>> ages_;  // (seconds since start, age of the prediction in ms)
  long udp_sockets_ = 0, udp_drops_ = 0;
};

int Soak::report() {
  int failures = 0;
  auto check = [&](bool ok, const std::string& what) {
    std::cout << (ok ? "  ok    " : "  FAIL  ") << what << "\n";
    if (!ok) ++failures;
  };
  std::cout << "\nsoak: " << duration_ << " s, " << blocks_ << " blocks, " << fps_ << " frames/s, "
            << frame_number_ << " frames published" << (drill_ ? ", fault drill" : "") << "\n";
  std::cout << "module       pid(s)        RSS start->end MB   peak (HWM) start->end MB  received published dropped errors "
               "restarts worst-hb-gap s\n";
  for (const auto& name : watched()) {
    const ModuleWatch& w = watch_.at(name);
    std::ostringstream pids;
    for (int p : w.pids) pids << (pids.tellp() ? "," : "") << p;
    char line[300];
    std::snprintf(line, sizeof line, "%-12s %-13s %7.1f -> %7.1f   %9.1f -> %9.1f     %8lld %9lld %7lld %6lld %8d %8.2f\n", name.c_str(),
                  pids.str().c_str(), w.mem_start.rss_kb / 1024.0, w.mem_end.rss_kb / 1024.0, w.mem_start.hwm_kb / 1024.0,
                  w.mem_end.hwm_kb / 1024.0,
                  (long long)(w.retired_received + w.last.received), (long long)(w.retired_published + w.last.published),
                  (long long)(w.retired_dropped + w.last.dropped), (long long)(w.retired_errors + w.last.errors),
                  w.restarts, w.worst_gap);
    std::cout << line;
  }
  std::cout << "checks:\n";
  for (const auto& name : watched()) {
    const ModuleWatch& w = watch_.at(name);
    check(w.mem_end.rss_kb > 0 && w.mem_end.rss_kb <= w.mem_start.rss_kb * max_rss_growth_ + 20 * 1024,
          name + ": resident memory bounded (end " + std::to_string(w.mem_end.rss_kb / 1024) + " MB <= " +
              std::to_string(max_rss_growth_) + " x start + 20 MB)");
    check(w.worst_gap <= 2.5, name + ": heartbeats continuous (worst gap " + std::to_string(w.worst_gap) + " s outside its own drill)");
    if (name == "prediction") {  // one answer (possibly an error status) per stack it did not drop
      const int64_t b = backlog(w.last);
      check(b <= 10 && b >= -10, name + ": no queue growth (received - published - dropped = " + std::to_string(b) +
                                     " at the end, " + std::to_string(w.backlog_mid) + " at mid-run)");
    }
    if (!drill_ || name == kLogger) check(w.pids.size() == 1, name + ": one process for the whole run (never restarted)");
  }
  // Queue growth, end to end: prediction ages in the first and last fifth of the run.
  auto median_age = [&](double from, double to) {
    std::vector<double> a;
    for (const auto& [t, age] : ages_)
      if (t >= from && t < to) a.push_back(age);
    if (a.empty()) return -1.0;
    std::sort(a.begin(), a.end());
    return a[a.size() / 2];
  };
  const double age_start = median_age(0, duration_ / 5), age_end = median_age(duration_ * 4 / 5, duration_);
  check(age_start >= 0 && age_end >= 0 && age_end <= 2 * age_start + 50,
        "no queue growth end to end: median age of a prediction (now - camera frame utime) " + std::to_string(age_start) +
            " ms in the first fifth, " + std::to_string(age_end) + " ms in the last fifth (limit 2x + 50 ms)");
  // Drills.
  double slowest_restart = 0;
  if (drill_) {
    for (const auto& d : drill_log_) {
      const bool ok = d.restarted_after >= 0 && d.restarted_after <= restart_limit_ && d.new_restarts == d.old_restarts + 1;
      slowest_restart = std::max(slowest_restart, d.restarted_after);
      check(ok, "drill: kill -9 " + d.module + " (pid " + std::to_string(d.old_pid) + ") at " + std::to_string(int(d.at)) +
                    " s: back as pid " + std::to_string(d.new_pid) + " with restarts " + std::to_string(d.new_restarts) +
                    " after " + std::to_string(d.restarted_after) + " s");
    }
    check(drill_log_.size() == kModules.size(), "drill: every module killed once (" + std::to_string(drill_log_.size()) + ")");
    for (const auto& name : kModules) {
      const ModuleWatch& w = watch_.at(name);
      check(w.pids.size() == 2, name + ": exactly two processes (the original and its restart), others untouched: " +
                                    std::to_string(w.pids.size()));
    }
  }
  // The logger's own account of what it lost (its last heartbeat before the stop).
  {
    const heartbeat_t& lg = watch_.at(kLogger).last;
    const double kernel = value_of(lg, "kernel_drops"), gaps = value_of(lg, "sequence_gaps");
    std::cout << "logger: " << lg.received << " messages received, " << lg.published << " written, "
              << value_of(lg, "bytes_written") / 1e6 << " MB in " << value_of(lg, "files") << " file(s), queue peak "
              << value_of(lg, "queue_peak_bytes") / 1e6 << " MB, receive buffer " << value_of(lg, "rcvbuf_bytes") / 1e6
              << " MB, status '" << lg.status << "'\n";
    check(lg.dropped == 0 && lg.errors == 0 && kernel == 0 && gaps == 0,
          "logger: nothing lost (" + std::to_string(lg.dropped) + " queue-full drops, " + std::to_string(int64_t(kernel)) +
              " kernel drops on its socket, " + std::to_string(int64_t(gaps)) + " camera frame-number gaps, " +
              std::to_string(lg.errors) + " write errors)");
  }
  // The log.
  std::vector<fs::path> logs;
  for (const auto& e : fs::directory_iterator(out_dir_))
    if (e.path().filename().string().rfind("soak-log", 0) == 0) logs.push_back(e.path());
  std::sort(logs.begin(), logs.end());
  std::set<int64_t> logged;
  std::vector<int64_t> times;
  int64_t logged_messages = 0, corrupt = 0;
  std::vector<bool> frame_logged(static_cast<size_t>(frame_number_), false);
  const std::string image_channel = channel(kImageChannel);
  for (const auto& path : logs) {
    auto log = std::make_unique<lcm::LogFile>(path.string(), "r");
    if (!log->good()) continue;
    while (const lcm::LogEvent* ev = log->readNextEvent()) {
      if (ev->channel == image_channel) {
        image_t img{};
        if (img.decode(ev->data, 0, ev->datalen) >= 0 && img.source == "soak" && img.frame_number >= 0 &&
            img.frame_number < frame_number_)
          frame_logged[static_cast<size_t>(img.frame_number)] = true;
        continue;
      }
      if (ev->channel != channel(kPredictionChannel)) continue;
      prediction_t p{};
      if (p.decode(ev->data, 0, ev->datalen) < 0) {
        ++corrupt;
        continue;
      }
      ++logged_messages;
      logged.insert(p.frame_number);
      times.push_back(ev->timestamp);
    }
  }
  std::sort(times.begin(), times.end());
  double worst_gap = 0;
  for (size_t i = 1; i < times.size(); ++i) worst_gap = std::max(worst_gap, (times[i] - times[i - 1]) / 1e6);
  std::cout << "udp: " << udp_drops_ << " datagrams dropped by the kernel (receive buffers full) over " << udp_sockets_
            << " sockets on the bus port, sampled before the stop\n";
  int64_t missing = 0;
  std::string missing_list;
  for (int64_t f : seen_predictions_) {
    if (logged.count(f)) continue;
    if (++missing <= 10) missing_list += " " + std::to_string(f);
  }
  if (missing)
    std::cout << "log: missing frames" << missing_list << (missing > 10 ? " ..." : "") << " (logged frames "
              << (logged.empty() ? -1 : *logged.begin()) << ".." << (logged.empty() ? -1 : *logged.rbegin()) << ")\n";
  const ModuleWatch& pw = watch_.at("prediction");
  const int64_t published = pw.retired_published + pw.last.published;
  std::cout << "log: " << logs.size() << " file(s), " << logged_messages << " prediction_t (" << logged.size()
            << " distinct frames), " << seen_predictions_.size() << " seen on the bus, worst gap " << worst_gap << " s\n";
  check(!logs.empty() && corrupt == 0, "log: readable, no undecodable prediction_t (" + std::to_string(corrupt) + ")");
  check(missing == 0, "log complete: every prediction seen on the bus is logged (" + std::to_string(missing) + " missing)");
  check(logged_messages >= published && published > 0,
        "log complete: " + std::to_string(logged_messages) + " logged >= " + std::to_string(published) +
            " published by the prediction processes (their heartbeats)");
  const int64_t frames_logged = std::count(frame_logged.begin(), frame_logged.end(), true);
  check(frames_published_ == frame_number_ && frames_logged == frame_number_,
        "log complete: every camera frame published is logged (" + std::to_string(frames_logged) + " of " +
            std::to_string(frame_number_) + ", " + std::to_string(frame_number_ - frames_published_) +
            " refused by LCM at publish)");
  const double gap_limit = drill_ ? slowest_restart + 1.0 : 1.0;
  check(worst_gap <= gap_limit, "log: no gap between predictions longer than " + std::to_string(gap_limit) + " s (" +
                                    (drill_ ? "slowest restart + 1 s" : "no drill") + "): worst " + std::to_string(worst_gap) + " s");
  std::cout << (failures ? "SOAK FAILED: " + std::to_string(failures) + " check(s)" : std::string("SOAK PASSED")) << "\n";
  return failures ? 1 : 0;
}

int Main(int argc, char** argv) {
  Flags f("bricklayer-soak", "the pipeline under load for a bounded time, with fault drills; exit 1 on any failed check");
  f.add("duration", "60", "seconds of load (the run takes ~15 s more for start-up and the checks)");
  f.add("blocks", "200", "blocks in every rendered pile");
  f.add("fps", "60", "camera frames per second");
  f.add("frames", "8", "distinct rendered frames, cycled");
  f.add_bool("drill", "kill -9 each module in turn during the run");
  f.add("restart-limit", "10", "seconds a killed module may take to come back");
  f.add("max-rss-growth", "1.5", "end RSS must be <= this times the start RSS + 20 MB");
  f.add("bin-dir", "", "the build's bin directory (bricklayer-launch and the modules)");
  f.add("root", ".", "project root (for the launcher)");
  f.add("out-dir", "logs/soak", "where the profile, the launcher's output and the log go");
  f.add("lcm-url", "", "LCM URL (default: $LCM_DEFAULT_URL, else host-only udpm ttl=0)");
  f.add("log-level", "info", "debug, info, warn or error");
  if (!f.parse(argc, argv)) return 0;
  check_lcm_url(resolve_lcm_url(f.get("lcm-url")));
  if (f.get("bin-dir").empty()) throw FlagError("--bin-dir is required");
  Soak soak(f);
  return soak.run();
}

}  // namespace
}  // namespace bricklayer

int main(int argc, char** argv) { return bricklayer::run_main("bricklayer-soak", &bricklayer::Main, argc, argv); }
