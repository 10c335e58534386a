// NETNS, real processes: a camera host and a projector host, two network namespaces joined by a veth
// pair (created inside this test's own private namespace, so names cannot clash and everything
// disappears with it). Stacks published on the camera host produce predictions on the projector host
// with the LAN URL (ttl=1); with the host-only URL (ttl=0) nothing crosses.
#include <catch2/catch.hpp>

#include <unistd.h>

#include <filesystem>

#include "harness/program.h"
#include "harness/scratch.h"

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
  const harness::Ran ran = harness::run_program("/bin/sh", {"-c", command}, 10s);
  INFO(command << "\n" << ran.err);
  REQUIRE(ran.status.clean());
}

// A "host": a network namespace held open by a sleeping process, joined to the other by a veth end.
struct Host {
  harness::Program anchor{"/usr/bin/unshare", {"-n", "/bin/sleep", "300"}};
  std::string pid;
  Host() {
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
  // A program of the build (target name) run inside this host's namespace.
  harness::Program run(const std::string& target, std::vector<std::string> args) {
    args.insert(args.begin(), {"-t", pid, "-n", harness::program_path(target)});
    return harness::Program("/usr/bin/nsenter", args);
  }
};

}  // namespace

TEST_CASE("stacks published on the camera host produce predictions on the projector host (ttl=1 over veth)") {
  Host camera, projector;
  sh("ip link add blcam type veth peer name blproj");
  camera.configure("blcam", "10.201.0.1/24");
  projector.configure("blproj", "10.201.0.2/24");
  harness::Program prediction = projector.run("bricklayer-prediction", {"--lcm-url", kLanUrl});

  // The camera host's client waits for the prediction's heartbeat (projector -> camera), then sends
  // stacks and checks every answer byte for byte against the logic run locally (camera -> projector -> camera).
  harness::Program client = camera.run("bricklayer-bench-roundtrip", {"--no-spawn", "--verify", "--blocks", "5,25", "--count",
                                                                      "40", "--warmup", "0", "--lcm-url", kLanUrl});
  auto st = client.wait_exit(60s);
  REQUIRE(st);
  const std::string out = client.stdout_text() + client.stderr_text();
  INFO(out);
  CHECK(st->clean());  // exit 0: no lost round trips, no mismatches
  CHECK(out.find("     25 ") != std::string::npos);

  SECTION("with the host-only URL (ttl=0) no stack leaves the camera host") {
    harness::Program local = camera.run("bricklayer-bench-roundtrip", {"--no-spawn", "--blocks", "5", "--count", "3", "--warmup",
                                                                       "0", "--timeout-ms", "300", "--lcm-url",
                                                                       "udpm://239.255.76.67:7667?ttl=0"});
    auto lst = local.wait_exit(30s);
    REQUIRE(lst);
    const std::string lout = local.stdout_text() + local.stderr_text();
    INFO(lout);
    // It hears the projector's heartbeats (sent with ttl=1), but its own ttl=0 stacks stay home: all lost.
    CHECK(lst->code == 1);
    CHECK(lout.find("      3 ") != std::string::npos);
  }
  prediction.stop();
}
