// bricklayer-bench-e2e: end-to-end latency, camera frame published -> projection frame presented,
// through the real processes (vision, prediction, projection --headless). Run inside a private network
// namespace (as root: the two-host setup creates a namespace and a veth pair), e.g.
//   tests/netns/run-in-netns build/bin/bricklayer-bench-e2e --bin-dir build/bin
// For each block count (--blocks 25,60,200) and each setup:
//   one-host:  everything in this namespace, host-only URL (ttl=0);
//   two-hosts: this namespace is the camera host (this benchmark's frames + vision), a second namespace
//              joined by a veth pair is the projector host (prediction + projection), LAN URL (ttl=1).
// Publishes BL_IMAGE (simcam renders, JPEG) at --fps; subscribes BL_TIMING. The latency of a frame is
// the projection's timing_t "present" (received_utime + elapsed_us, wall clock) minus the wall clock
// when this benchmark published the frame (both namespaces share the clock). Prints median and p99 per
// row; frames that never reach the screen (newest-wins drops) are counted, not timed.
#include <lcm/lcm-cpp.hpp>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <iomanip>
#include <iostream>
#include <map>
#include <memory>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "bricklayer/common/channels.h"
#include "bricklayer/common/flags.h"
#include "bricklayer/heartbeat_t.hpp"
#include "bricklayer/image_t.hpp"
#include "bricklayer/launcher/process.h"
#include "bricklayer/stack_t.hpp"
#include "bricklayer/timing_t.hpp"
#include "frames.h"

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;
using namespace std::chrono_literals;

namespace bricklayer {
namespace {

constexpr const char* kHostUrl = "udpm://239.255.76.67:7667?ttl=0";
constexpr const char* kLanUrl = "udpm://239.255.76.67:7667?ttl=1";
constexpr int64_t kFramesPerPile = 30;

int64_t wall_us() {
  return std::chrono::duration_cast<std::chrono::microseconds>(std::chrono::system_clock::now().time_since_epoch())
      .count();
}

void sh(const std::string& command) {
  auto p = launcher::Process::spawn({"/bin/sh", "-c", command});
  auto st = p.wait_for(10s);
  if (!st || !st->clean()) throw std::runtime_error("setup command failed: " + command);
}

std::string netns_of(pid_t pid) {
  std::error_code ec;
  return fs::read_symlink("/proc/" + std::to_string(pid) + "/ns/net", ec).string();
}

// The projector host: a network namespace held by a sleeping process, joined to ours by a veth pair.
class ProjectorHost {
 public:
  ProjectorHost() {
    anchor_ = launcher::Process::spawn({"/usr/bin/unshare", "-n", "/bin/sleep", "100000"});
    const std::string mine = netns_of(::getpid());
    for (int i = 0; i < 400 && (netns_of(anchor_.pid()).empty() || netns_of(anchor_.pid()) == mine); ++i) usleep(5000);
    if (netns_of(anchor_.pid()) == mine) throw std::runtime_error("could not create the projector host's namespace");
    pid_ = std::to_string(anchor_.pid());
    sh("ip link add bl-e2e-cam type veth peer name bl-e2e-proj");
    sh("ip addr add 10.202.0.1/24 dev bl-e2e-cam && ip link set bl-e2e-cam multicast on && ip link set bl-e2e-cam up"
       " && ip route replace 224.0.0.0/4 dev bl-e2e-cam");
    sh("ip link set bl-e2e-proj netns " + pid_);
    sh("/usr/bin/nsenter -t " + pid_ + " -n sh -c 'ip link set lo up && ip addr add 10.202.0.2/24 dev bl-e2e-proj && "
       "ip link set bl-e2e-proj multicast on && ip link set bl-e2e-proj up && ip route add 224.0.0.0/4 dev bl-e2e-proj'");
  }
  ~ProjectorHost() {
    try {
      sh("ip link del bl-e2e-cam 2>/dev/null; ip route replace 224.0.0.0/4 dev lo");
    } catch (...) {
    }
  }
  std::vector<std::string> wrap(std::vector<std::string> argv) const {
    argv.insert(argv.begin(), {"/usr/bin/nsenter", "-t", pid_, "-n"});
    return argv;
  }

 private:
  launcher::Process anchor_;
  std::string pid_;
};

struct Row {
  std::string setup;
  int blocks = 0;
  size_t published = 0, presented = 0;
  double detected = 0;
  double median_ms = 0, p99_ms = 0, max_ms = 0;
  std::string breakdown;  // median ms after publication at which each module received / finished a frame
};

class Bench {
 public:
  Bench(const std::string& url) : lcm_(std::make_unique<lcm::LCM>(url)) {
    if (lcm_->getFileno() < 0) throw std::runtime_error("cannot open the LCM bus " + url);
    lcm_->subscribe(channel(kTimingChannel), &Bench::OnTiming, this)->setQueueCapacity(10000);
    lcm_->subscribe(channel(kStackChannel), &Bench::OnStack, this)->setQueueCapacity(1000);
    lcm_->subscribe(channel(kHeartbeatChannel), &Bench::OnHeartbeat, this)->setQueueCapacity(1000);
  }

  Row run(const std::string& setup, int blocks, const reliability::Frames& frames, double fps, double seconds,
          double warmup) {
    // Wait for the three modules.
    auto t0 = Clock::now();
    while ((modules_.size() < 3) && Clock::now() - t0 < 20s) lcm_->handleTimeout(20);
    if (modules_.size() < 3) throw std::runtime_error(setup + ": the modules sent no heartbeats within 20 s");
    published_.clear();
    presented_.clear();
    stacks_ = 0;
    blocks_seen_ = 0;
    stages_.clear();
    int64_t frame = 1000000 * blocks;  // distinct frame numbers per row
    const auto start = Clock::now();
    const double total = warmup + seconds;
    double next = 0;
    size_t counted = 0;
    int64_t first_counted = -1;
    while (true) {
      const double t = std::chrono::duration<double>(Clock::now() - start).count();
      if (t >= total) break;
      if (t >= next) {
        image_t m{};
        m.frame_number = frame++;
        m.width = frames.size.width;
        m.height = frames.size.height;
        m.format = image_t::FORMAT_JPEG;
        m.source = "bench-e2e";
        // Each pile stays in view for half a second, as a player's pile does: vision's temporal filter
        // confirms its blocks, so the stack (and the work downstream) has the row's block count.
        m.data = frames.jpeg[static_cast<size_t>(m.frame_number / kFramesPerPile) % frames.jpeg.size()];
        m.size = static_cast<int32_t>(m.data.size());
        m.utime = wall_us();
        lcm_->publish(channel(kImageChannel), &m);
        if (t >= warmup) {
          if (first_counted < 0) first_counted = m.frame_number;
          published_[m.frame_number] = m.utime;
          ++counted;
        }
        next += 1.0 / fps;
      }
      const int ms = static_cast<int>(std::max(0.0, (next - t) * 1000));
      lcm_->handleTimeout(std::max(1, ms));
    }
    const auto drain = Clock::now();
    while (Clock::now() - drain < 500ms) lcm_->handleTimeout(10);
    std::vector<double> lat;
    for (const auto& [f, present] : presented_) {
      auto it = published_.find(f);
      if (it != published_.end()) lat.push_back((present - it->second) / 1000.0);
    }
    std::sort(lat.begin(), lat.end());
    Row r;
    r.setup = setup;
    r.blocks = blocks;
    r.published = counted;
    r.presented = lat.size();
    r.detected = stacks_ ? static_cast<double>(blocks_seen_) / stacks_ : 0;
    if (!lat.empty()) {
      r.median_ms = lat[lat.size() / 2];
      r.p99_ms = lat[std::min(lat.size() - 1, static_cast<size_t>(0.99 * lat.size()))];
      r.max_ms = lat.back();
    }
    // Where the time goes, for the frames that reached the screen: median ms after the camera published
    // the frame at which each module received it and finished with it.
    std::ostringstream breakdown;
    for (const char* module : {"vision", "prediction", "projection"}) {
      std::vector<double> in, out;
      for (const auto& [f, present] : presented_) {
        const auto pub = published_.find(f);
        const auto& m = stages_[module];
        const auto st = m.find(f);
        if (pub == published_.end() || st == m.end()) continue;
        in.push_back((st->second.first - pub->second) / 1000.0);
        out.push_back((st->second.first + st->second.second - pub->second) / 1000.0);
      }
      if (in.empty()) continue;
      std::nth_element(in.begin(), in.begin() + in.size() / 2, in.end());
      std::nth_element(out.begin(), out.begin() + out.size() / 2, out.end());
      breakdown << (breakdown.tellp() > 0 ? ", " : "") << module << " in " << std::fixed << std::setprecision(2)
                << in[in.size() / 2] << " done " << out[out.size() / 2];
    }
    r.breakdown = breakdown.str();
    return r;
  }

 private:
  void OnTiming(const lcm::ReceiveBuffer*, const std::string&, const timing_t* t) {
    if (t->module == "projection" && t->stage == "present") presented_[t->frame_number] = t->received_utime + t->elapsed_us;
    stages_[t->module][t->frame_number] = {t->received_utime, t->elapsed_us};
  }
  void OnStack(const lcm::ReceiveBuffer*, const std::string&, const stack_t* s) {
    ++stacks_;
    blocks_seen_ += s->num_blocks;
  }
  void OnHeartbeat(const lcm::ReceiveBuffer*, const std::string&, const heartbeat_t* h) {
    if (h->module == "vision" || h->module == "prediction" || h->module == "projection") modules_[h->module] = h->pid;
  }

  std::unique_ptr<lcm::LCM> lcm_;
  std::map<int64_t, int64_t> published_, presented_;
  // module -> frame -> (received wall clock, elapsed us), for the per-stage breakdown.
  std::map<std::string, std::map<int64_t, std::pair<int64_t, int64_t>>> stages_;
  std::map<std::string, int> modules_;
  int64_t stacks_ = 0, blocks_seen_ = 0;
};

std::vector<launcher::Process> start_modules(const std::string& bin, const std::string& url, const ProjectorHost* proj,
                                             const std::string& log_dir) {
  std::vector<launcher::Process> out;
  auto spawn = [&](std::vector<std::string> argv, bool on_projector) {
    launcher::SpawnOptions o;
    o.env = {"LCM_DEFAULT_URL=" + url, "SDL_VIDEODRIVER=offscreen", "SDL_AUDIODRIVER=dummy"};
    o.stdout_path = log_dir + "/" + fs::path(argv[0]).filename().string() + ".log";
    o.merge_stderr = true;
    argv[0] = bin + "/" + argv[0];
    if (on_projector && proj) argv = proj->wrap(argv);
    out.push_back(launcher::Process::spawn(argv, o));
  };
  spawn({"bricklayer-projection", "--headless", "--log-level", "warn"}, true);
  spawn({"bricklayer-prediction", "--log-level", "warn"}, true);
  spawn({"bricklayer-vision", "--log-level", "warn"}, false);
  return out;
}

std::vector<int> parse_blocks(const std::string& s) {
  std::vector<int> out;
  std::stringstream in(s);
  std::string item;
  while (std::getline(in, item, ',')) out.push_back(std::stoi(item));
  if (out.empty()) throw FlagError("--blocks: give a comma-separated list, e.g. 25,60,200");
  return out;
}

int Main(int argc, char** argv) {
  Flags f("bricklayer-bench-e2e", "camera frame published -> projection frame presented, median and p99");
  f.add("bin-dir", "", "the build's bin directory");
  f.add("blocks", "25,60,200", "block counts, comma-separated");
  f.add("fps", "60", "camera frames per second");
  f.add("seconds", "10", "measured seconds per row (after the warm-up)");
  f.add("warmup", "2", "seconds per row before measuring");
  f.add("setups", "one-host,two-hosts", "which setups: one-host, two-hosts");
  f.add("log-dir", "/tmp", "where the modules' output goes");
  f.add("log-level", "warn", "debug, info, warn or error");
  if (!f.parse(argc, argv)) return 0;
  if (f.get("bin-dir").empty()) throw FlagError("--bin-dir is required");
  const auto blocks = parse_blocks(f.get("blocks"));
  const std::string setups = f.get("setups");
  std::vector<Row> rows;
  std::map<int, reliability::Frames> frames;
  for (int n : blocks) frames[n] = reliability::render_frames(n, 8);
  for (const std::string setup : {"one-host", "two-hosts"}) {
    if (setups.find(setup) == std::string::npos) continue;
    std::unique_ptr<ProjectorHost> proj;
    if (setup == std::string("two-hosts")) proj = std::make_unique<ProjectorHost>();
    const std::string url = proj ? kLanUrl : kHostUrl;
    for (int n : blocks) {
      auto procs = start_modules(f.get("bin-dir"), url, proj.get(), f.get("log-dir"));
      {
        Bench bench(url);
        rows.push_back(bench.run(setup, n, frames[n], f.get_double("fps"), f.get_double("seconds"), f.get_double("warmup")));
      }
      for (auto& p : procs) p.stop(5s);
      const Row& r = rows.back();
      std::fprintf(stderr, "%s %d blocks: median %.2f ms p99 %.2f ms (%zu of %zu frames presented)\n", r.setup.c_str(),
                   r.blocks, r.median_ms, r.p99_ms, r.presented, r.published);
      std::fprintf(stderr, "  where the time goes (median ms after publication): %s\n", r.breakdown.c_str());
    }
  }
  std::printf("| setup | blocks (detected) | frames published | presented | median ms | p99 ms | max ms |\n");
  std::printf("|---|---|---|---|---|---|---|\n");
  for (const Row& r : rows)
    std::printf("| %s | %d (%.0f) | %zu | %zu | %.2f | %.2f | %.2f |\n", r.setup.c_str(), r.blocks, r.detected, r.published,
                r.presented, r.median_ms, r.p99_ms, r.max_ms);
  return 0;
}

}  // namespace
}  // namespace bricklayer

int main(int argc, char** argv) { return bricklayer::run_main("bricklayer-bench-e2e", &bricklayer::Main, argc, argv); }
