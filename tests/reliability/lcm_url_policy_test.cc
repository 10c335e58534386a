// Every process: the default LCM URL stays on this host (ttl=0), and a URL that would route the bus
// beyond the local network (ttl > 1, also when hidden behind an earlier ttl=0 option) or names an
// unknown provider is refused at start with a clear error and a non-zero exit -- before the process
// opens the bus. Runs each real binary.
#include <catch2/catch.hpp>

#include <unistd.h>

#include <filesystem>
#include <set>

#include "bricklayer/common/channels.h"
#include "bricklayer/common/lcm_url.h"
#include "bricklayer/heartbeat_t.hpp"
#include "bricklayer/launcher/process.h"
#include "bricklayer/runtime/lcm_bus.h"
#include "harness/recorder.h"
#include "harness/scratch.h"

using namespace bricklayer;
using namespace std::chrono_literals;
namespace fs = std::filesystem;

namespace {

const std::vector<std::vector<std::string>> kBinaries = {
    {"bricklayer-prediction"},
    {"bricklayer-vision"},
    {"bricklayer-projection", "--headless"},
    {"bricklayer-planner"},
    {"bricklayer-calibrate", "--serve"},
};

struct Outcome {
  launcher::ExitStatus status;
  std::string output;
};

Outcome run(std::vector<std::string> argv, const std::vector<std::string>& env = {}) {
  argv[0] = harness::program_path(argv[0]);
  launcher::SpawnOptions o;
  o.env = env;
  o.env.push_back("SDL_VIDEODRIVER=offscreen");
  o.env.push_back("SDL_AUDIODRIVER=dummy");
  o.stdout_path = fs::temp_directory_path() / ("bricklayer-url-" + std::to_string(::getpid()) + ".log");
  o.merge_stderr = true;
  auto p = launcher::Process::spawn(argv, o);
  auto st = p.wait_for(10s);
  if (!st) st = p.stop(2s);
  return {*st, harness::read_file(o.stdout_path)};
}

}  // namespace

TEST_CASE("the default LCM URL is host-only (ttl=0)") {
  ::unsetenv("LCM_DEFAULT_URL");
  CHECK(resolve_lcm_url("") == kDefaultLcmUrl);
  CHECK(std::string(kDefaultLcmUrl).find("ttl=0") != std::string::npos);
  CHECK_NOTHROW(check_lcm_url(kDefaultLcmUrl));
  CHECK_NOTHROW(check_lcm_url("udpm://239.255.76.67:7667?ttl=1"));
  CHECK_THROWS_AS(check_lcm_url("udpm://239.255.76.67:7667?ttl=2"), std::invalid_argument);
  // LCM keeps the last value of a repeated option: ttl=0 first must not hide ttl=5 after it.
  CHECK_THROWS_AS(check_lcm_url("udpm://239.255.76.67:7667?ttl=0&ttl=5"), std::invalid_argument);
  CHECK_THROWS_AS(check_lcm_url("udpm://239.255.76.67:7667?recv_buf_size=100000&ttl=255"), std::invalid_argument);
  CHECK_THROWS_AS(check_lcm_url("http://example.org"), std::invalid_argument);
}

TEST_CASE("every process refuses a routed URL (ttl > 1) with a clear error and a non-zero exit") {
  for (const auto& base : kBinaries) {
    for (const std::string url : {"udpm://239.255.76.67:7667?ttl=2", "udpm://239.255.76.67:7667?ttl=0&ttl=32",
                                  "bogus://nowhere"}) {
      INFO(base[0] << " --lcm-url " << url);
      auto argv = base;
      argv.push_back("--lcm-url=" + url);
      const Outcome flag = run(argv);
      INFO(flag.output);
      CHECK(!flag.status.clean());
      CHECK(flag.status.signal == 0);  // an error exit, not a crash
      CHECK((flag.output.find("ttl") != std::string::npos || flag.output.find("provider") != std::string::npos));
      // The same URL from the environment is refused the same way.
      const Outcome env = run(base, {"LCM_DEFAULT_URL=" + url});
      INFO(env.output);
      CHECK(!env.status.clean());
      CHECK(env.status.signal == 0);
    }
  }
}

namespace {

std::string netns_of(pid_t pid) {
  std::error_code ec;
  return fs::read_symlink("/proc/" + std::to_string(pid) + "/ns/net", ec).string();
}

void sh(const std::string& command) {
  INFO(command);
  auto p = launcher::Process::spawn({"/bin/sh", "-c", command});
  auto st = p.wait_for(10s);
  REQUIRE(st);
  REQUIRE(st->clean());
}

std::string work_dir() { return fs::temp_directory_path() / ("bricklayer-url-" + std::to_string(::getpid())); }

// Starts every binary in the namespace of `anchor` with the given environment; returns the processes.
std::vector<launcher::Process> start_all(const std::string& anchor, const std::vector<std::string>& env) {
  std::vector<launcher::Process> out;
  for (const auto& base : kBinaries) {
    std::vector<std::string> argv = {"/usr/bin/nsenter", "-t", anchor, "-n", harness::program_path(base[0])};
    argv.insert(argv.end(), base.begin() + 1, base.end());
    argv.insert(argv.end(), {"--log-level", "error"});
    launcher::SpawnOptions o;
    o.env = env;
    o.env.push_back("SDL_VIDEODRIVER=offscreen");
    o.env.push_back("SDL_AUDIODRIVER=dummy");
    o.cwd = work_dir();  // calibrate --serve reads calibration.json here
    o.stdout_path = fs::temp_directory_path() / ("bricklayer-url-" + base[0] + "-" + std::to_string(::getpid()) + ".log");
    o.merge_stderr = true;
    out.push_back(launcher::Process::spawn(argv, o));
  }
  return out;
}

}  // namespace

TEST_CASE("with the default URL no process is heard on another host, with ttl=1 every one is") {
  // This namespace is the "other host"; a second namespace joined by a veth pair runs every binary.
  ::unsetenv("LCM_DEFAULT_URL");
  fs::create_directories(work_dir());
  {
    launcher::SpawnOptions o;
    o.cwd = work_dir();
    auto w = launcher::Process::spawn({harness::program_path("bricklayer-calibrate"), "--write-default", "--output=calibration.json"}, o);
    auto st = w.wait_for(10s);
    REQUIRE(st);
    REQUIRE(st->clean());
  }
  auto anchor = launcher::Process::spawn({"/usr/bin/unshare", "-n", "/bin/sleep", "300"});
  const std::string mine = netns_of(::getpid());
  for (int i = 0; i < 400 && (netns_of(anchor.pid()).empty() || netns_of(anchor.pid()) == mine); ++i) usleep(5000);
  REQUIRE(netns_of(anchor.pid()) != mine);
  const std::string pid = std::to_string(anchor.pid());
  sh("ip link add bl-url-a type veth peer name bl-url-b");
  sh("ip addr add 10.203.0.1/24 dev bl-url-a && ip link set bl-url-a multicast on && ip link set bl-url-a up"
     " && ip route replace 224.0.0.0/4 dev bl-url-a");
  sh("ip link set bl-url-b netns " + pid);
  sh("/usr/bin/nsenter -t " + pid + " -n sh -c 'ip link set lo up && ip addr add 10.203.0.2/24 dev bl-url-b && "
     "ip link set bl-url-b multicast on && ip link set bl-url-b up && ip route add 224.0.0.0/4 dev bl-url-b'");

  runtime::LcmBus other_bus("udpm://239.255.76.67:7667?ttl=1");
  REQUIRE(other_bus.open());
  harness::Recorder other_host = harness::Recorder::live(other_bus, {channel(kHeartbeatChannel)});
  auto modules_heard = [&] {
    std::set<std::string> heard;
    for (const heartbeat_t& hb : other_host.all<heartbeat_t>(channel(kHeartbeatChannel))) heard.insert(hb.module);
    return heard;
  };

  {
    auto procs = start_all(pid, {});  // no --lcm-url, no LCM_DEFAULT_URL: the built-in default
    other_host.pump_for(3500ms);      // every module heartbeats once a second
    for (size_t i = 0; i < procs.size(); ++i) {
      INFO(kBinaries[i][0] << ": " << harness::read_file(fs::temp_directory_path() / ("bricklayer-url-" + kBinaries[i][0] + "-" +
                                                                              std::to_string(::getpid()) + ".log")));
      CHECK(procs[i].running());
    }
    CHECK(modules_heard().empty());
    for (auto& p : procs) p.stop(5s);
  }
  {
    // Positive control: the same processes on the LAN URL are heard (the veth and routes work).
    auto procs = start_all(pid, {"LCM_DEFAULT_URL=udpm://239.255.76.67:7667?ttl=1"});
    const bool all = other_host.wait_until([&] { return modules_heard().size() == kBinaries.size(); }, 10s);
    std::string heard;
    for (const auto& m : modules_heard()) heard += m + " ";
    INFO("heard: " << heard);
    CHECK(all);
    for (auto& p : procs) p.stop(5s);
  }
  fs::remove_all(work_dir());
}
