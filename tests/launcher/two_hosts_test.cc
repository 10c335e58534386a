// NETNS, real processes: the exhibit's two machines as two network namespaces joined by a veth pair
// (inside this test's own namespace). Each runs bricklayer-launch with the LAN URL (ttl=1); an observer
// on the projector host sees both hosts' whole state; the camera host's link goes down for 7 s and up
// again (a switch power cycle: the route goes with it) and everything resumes with the same pids.
#include <catch2/catch.hpp>

#include <fcntl.h>
#include <sched.h>
#include <unistd.h>

#include <filesystem>
#include <map>
#include <thread>

#include <opencv2/imgcodecs.hpp>

#include "bricklayer/common/channels.h"
#include "bricklayer/heartbeat_t.hpp"
#include "bricklayer/host_state_t.hpp"
#include "bricklayer/image_t.hpp"
#include "bricklayer/launcher/supervisor.h"
#include "bricklayer/runtime/lcm_bus.h"
#include "harness/program.h"
#include "harness/recorder.h"
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
    for (int i = 0; i < 400 && (netns_of(anchor.pid()).empty() || netns_of(anchor.pid()) == mine); ++i) usleep(5000);
    REQUIRE(netns_of(anchor.pid()) != mine);
    pid = std::to_string(anchor.pid());
  }
  void configure(const std::string& dev, const std::string& address) {
    sh("ip link set " + dev + " netns " + pid);
    in("ip link set lo up && ip link set lo multicast on && ip addr add " + address + " dev " + dev +
       " && ip link set " + dev + " multicast on && ip link set " + dev + " up && ip route add 224.0.0.0/4 dev " + dev);
  }
  void in(const std::string& command) { sh("/usr/bin/nsenter -t " + pid + " -n sh -c '" + command + "'"); }
  harness::Program launch(const fs::path& root, const std::string& name, const std::string& dev) {
    return harness::Program("/usr/bin/nsenter",
                            {"-t", pid, "-n", harness::program_path("bricklayer-launch"), "--root", root.string(), "--bin-dir",
                             (harness::binary_dir() / "bin").string(), "--lcm-url", kLanUrl, "--host-name", name,
                             "--multicast-route", dev, (root / (name + ".json")).string()},
                            harness::ProgramOptions{{"DISPLAY="}, ""});
  }
};

std::map<std::string, host_state_t> newest_states(const harness::Recorder& rec) {
  std::map<std::string, host_state_t> out;
  for (const host_state_t& hs : rec.all<host_state_t>(channel(launcher::kHostStateChannel))) out[hs.host] = hs;
  return out;
}

}  // namespace

TEST_CASE("two hosts over a veth: an observer sees both hosts' state, and after the camera link is down 7 s and up all resume") {
  harness::ScratchDir root("two-hosts");
  fs::create_directories(root.path() / "frames");
  for (int k = 0; k < 3; ++k)
    cv::imwrite((root.path() / "frames" / ("f" + std::to_string(k) + ".png")).string(), cv::Mat(60, 80, CV_8UC3, cv::Scalar::all(40 * k)));
  harness::write_file(root / "camera-host.json",
                      R"({"modules":[{"name":"camera","command":["bricklayer-camera","--images","frames","--loop","--fps","10"]}]})");
  harness::write_file(root / "projector-host.json",
                      R"({"modules":[{"name":"prediction","command":["bricklayer-prediction","--log-level","warn"]}]})");
  Host camera, projector;
  sh("ip link add blcam type veth peer name blproj");
  camera.configure("blcam", "10.202.0.1/24");
  projector.configure("blproj", "10.202.0.2/24");
  harness::Program camera_launcher = camera.launch(root.path(), "camera-host", "blcam");
  harness::Program projector_launcher = projector.launch(root.path(), "projector-host", "blproj");

  // The observer lives on the projector host.
  const int ns = ::open(("/proc/" + projector.pid + "/ns/net").c_str(), O_RDONLY | O_CLOEXEC);
  REQUIRE(ns >= 0);
  REQUIRE(::setns(ns, CLONE_NEWNET) == 0);
  ::close(ns);
  std::map<std::string, host_state_t> states;
  pid_t camera_pid = 0;
  {
    runtime::LcmBus bus(kLanUrl);
    REQUIRE(bus.open());
    harness::Recorder rec = harness::Recorder::live(bus, {channel(launcher::kHostStateChannel)});
    REQUIRE(rec.wait_until([&] {
      states = newest_states(rec);
      return states.size() == 2 && states["camera-host"].modules_up == 1 && states["projector-host"].modules_up == 1;
    }, 20s));
    camera_pid = states["camera-host"].modules[0].pid;
    CHECK(states["camera-host"].modules[0].name == "camera");
    CHECK(states["projector-host"].modules[0].name == "prediction");
  }
  const pid_t prediction_pid = states["projector-host"].modules[0].pid;
  INFO(camera_launcher.stdout_text() << camera_launcher.stderr_text());

  // The camera host's link: down 7 s (beyond the 5 s heartbeat timeout), then up; its route is gone.
  camera.in("ip link set blcam down");
  std::this_thread::sleep_for(7s);
  camera.in("ip link set blcam up");

  runtime::LcmBus bus(kLanUrl);
  REQUIRE(bus.open());
  harness::Recorder rec = harness::Recorder::live(bus, {channel(launcher::kHostStateChannel), channel(kImageChannel)});
  REQUIRE(rec.wait_until([&] {
    states = newest_states(rec);
    return states.count("camera-host") && rec.count(channel(kImageChannel)) > 3;
  }, 20s));
  const host_state_t& cam = states["camera-host"];
  REQUIRE(cam.num_modules == 1);
  CHECK(cam.modules[0].pid == camera_pid);  // the same process: never killed as silent
  CHECK(cam.modules[0].restarts == 0);
  CHECK(cam.status == "ok");
  REQUIRE(states.count("projector-host"));
  CHECK(states["projector-host"].modules[0].pid == prediction_pid);
  CHECK(states["projector-host"].modules[0].restarts == 0);
  const std::string out = camera_launcher.stdout_text();
  CHECK(out.find("put the multicast route back: ip route replace 224.0.0.0/4 dev blcam") != std::string::npos);
  CHECK(out.find("silent for") == std::string::npos);
}
