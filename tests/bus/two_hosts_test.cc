// NETNS, real processes: a camera host and a projector host, two network namespaces joined by a veth
// pair (created inside this test's own private namespace, so names cannot clash and everything
// disappears with it). Stacks published on the camera host produce predictions on the projector host
// with the LAN URL (ttl=1); with the host-only URL (ttl=0) nothing crosses.
#include <catch2/catch.hpp>

#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <sstream>

#include "bricklayer/launcher/process.h"
#include "bus_test_util.h"

using namespace bricklayer;
using namespace std::chrono_literals;
namespace fs = std::filesystem;

namespace {

constexpr const char* kLanUrl = "udpm://239.255.76.67:7667?ttl=1";

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

// A "host": a network namespace held open by a sleeping process, joined to the other by a veth end.
struct Host {
  launcher::Process anchor;
  std::string pid;
  Host() {
    anchor = launcher::Process::spawn({"/usr/bin/unshare", "-n", "/bin/sleep", "300"});
    const std::string mine = netns_of(::getpid());
    for (int i = 0; i < 400 && (netns_of(anchor.pid()).empty() || netns_of(anchor.pid()) == mine); ++i)
      usleep(5000);
    REQUIRE(netns_of(anchor.pid()) != mine);
    pid = std::to_string(anchor.pid());
  }
  void configure(const std::string& dev, const std::string& address) {
    sh("ip link set " + dev + " netns " + pid);
    sh("/usr/bin/nsenter -t " + pid + " -n sh -c 'ip link set lo up && ip link set lo multicast on && ip addr add " +
       address + " dev " + dev + " && ip link set " + dev + " multicast on && ip link set " + dev +
       " up && ip route add 224.0.0.0/4 dev " + dev + "'");
  }
  launcher::Process run(std::vector<std::string> argv, const std::string& out_path) {
    argv.insert(argv.begin(), {"/usr/bin/nsenter", "-t", pid, "-n"});
    launcher::SpawnOptions o;
    o.stdout_path = out_path;
    o.merge_stderr = true;
    return launcher::Process::spawn(argv, o);
  }
};

std::string slurp(const std::string& p) {
  std::ifstream in(p);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

}  // namespace

TEST_CASE("stacks published on the camera host produce predictions on the projector host (ttl=1 over veth)") {
  Host camera, projector;
  sh("ip link add blcam type veth peer name blproj");
  camera.configure("blcam", "10.201.0.1/24");
  projector.configure("blproj", "10.201.0.2/24");
  const std::string dir = fs::temp_directory_path() / ("bricklayer-two-hosts-" + std::to_string(::getpid()));
  fs::create_directories(dir);

  auto prediction = projector.run({test::bin("bricklayer-prediction"), "--lcm-url", kLanUrl}, dir + "/prediction.out");

  // The camera host's client waits for the prediction's heartbeat (projector -> camera), then sends
  // stacks and checks every answer byte for byte against the logic run locally (camera -> projector -> camera).
  auto client = camera.run({test::bin("bricklayer-bench-roundtrip"), "--no-spawn", "--verify", "--blocks", "5,25",
                            "--count", "40", "--warmup", "0", "--lcm-url", kLanUrl},
                           dir + "/client.out");
  auto st = client.wait_for(60s);
  REQUIRE(st);
  std::string out = slurp(dir + "/client.out");
  INFO(out);
  CHECK(st->clean());  // exit 0: no lost round trips, no mismatches
  CHECK(out.find("     25 ") != std::string::npos);

  SECTION("with the host-only URL (ttl=0) no stack leaves the camera host") {
    auto local = camera.run({test::bin("bricklayer-bench-roundtrip"), "--no-spawn", "--blocks", "5", "--count", "3",
                             "--warmup", "0", "--timeout-ms", "300", "--lcm-url", "udpm://239.255.76.67:7667?ttl=0"},
                            dir + "/local.out");
    auto lst = local.wait_for(30s);
    REQUIRE(lst);
    std::string lout = slurp(dir + "/local.out");
    INFO(lout);
    // It hears the projector's heartbeats (sent with ttl=1), but its own ttl=0 stacks stay home: all lost.
    CHECK(lst->code == 1);
    CHECK(lout.find("      3 ") != std::string::npos);
  }
  prediction.stop(3s);
  std::error_code ec;
  fs::remove_all(dir, ec);
}
