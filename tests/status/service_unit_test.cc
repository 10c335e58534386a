// launch/setup --install-service PROFILE / --remove-service, into a temporary unit directory: the unit
// starts launch/bricklayer PROFILE, restarts it on failure, logs to the journal, sets the display for a
// profile with a projector window only, grants CAP_NET_ADMIN (and only it) with --multicast-route to the
// profiles that use the LAN, and passes systemd-analyze verify (when systemd is there).
#include <unistd.h>

#include <catch2/catch.hpp>

#include <filesystem>
#include <fstream>
#include <sstream>

#include "bricklayer/launcher/process.h"
#include "harness/program.h"
#include "harness/scratch.h"

using namespace bricklayer;
namespace fs = std::filesystem;

namespace {
const std::string kSetup = std::string(BRICKLAYER_SOURCE_DIR) + "/launch/setup";

harness::Ran setup(std::vector<std::string> args) {
  args.insert(args.begin(), kSetup);
  return harness::run_program("/bin/bash", args, std::chrono::seconds(30));
}

std::string slurp(const fs::path& p) {
  std::ifstream in(p);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

std::string me() {
  harness::Ran r = harness::run_program("/usr/bin/id", {"-un"});
  std::string name = r.out;
  while (!name.empty() && (name.back() == '\n' || name.back() == ' ')) name.pop_back();
  return name;
}

// systemd-analyze verify's verdict on a unit file, or nullopt without systemd-analyze.
std::optional<harness::Ran> verify(const fs::path& unit) {
  const std::string analyze = launcher::find_program("systemd-analyze", "", {});
  if (analyze.empty()) return std::nullopt;
  return harness::run_program(analyze, {"verify", unit.string()});
}
}  // namespace

TEST_CASE("launch/setup writes and removes the exhibit's systemd unit") {
  harness::ScratchDir dir("service");
  const fs::path units = dir / "units";
  const fs::path unit = units / "bricklayer.service";
  const std::string user = me();

  harness::Ran projector = setup({"--install-service", "projector-host", "--unit-dir", units.string(), "--user", user});
  INFO(projector.out << projector.err);
  REQUIRE(projector.status.clean());
  REQUIRE(fs::exists(unit));
  std::string text = slurp(unit);
  INFO(text);
  // The LAN profile's interface (its "multicast_route") goes to the launcher, with the one capability
  // `ip route replace` needs, and nothing else in the bounding set.
  CHECK(text.find("ExecStart=" + std::string(BRICKLAYER_SOURCE_DIR) +
                  "/launch/bricklayer projector-host --multicast-route eth0\n") != std::string::npos);
  CHECK(text.find("\nAmbientCapabilities=CAP_NET_ADMIN\n") != std::string::npos);
  CHECK(text.find("\nCapabilityBoundingSet=CAP_NET_ADMIN\n") != std::string::npos);
  CHECK(projector.out.find("multicast route on eth0 with CAP_NET_ADMIN") != std::string::npos);
  CHECK(text.find("\nRestart=on-failure\n") != std::string::npos);
  CHECK(text.find("\nStandardOutput=journal\n") != std::string::npos);
  CHECK(text.find("\nUser=" + user + "\n") != std::string::npos);
  CHECK(text.find("\nEnvironment=DISPLAY=:0\n") != std::string::npos);  // the projector's window
  CHECK(text.find("\nWantedBy=graphical.target\n") != std::string::npos);
  if (auto v = verify(unit)) {
    INFO(v->out << v->err);
    CHECK(v->status.clean());
  } else {
    WARN("systemd-analyze is not installed: the unit's syntax is not verified");
  }

  // The camera host has no window: no display, started with the multi-user target.
  harness::Ran camera = setup({"--install-service", "camera-host", "--unit-dir", units.string(), "--user", user,
                               "--display", ":1"});
  REQUIRE(camera.status.clean());
  text = slurp(unit);
  CHECK(text.find("DISPLAY") == std::string::npos);
  CHECK(text.find("\nWantedBy=multi-user.target\n") != std::string::npos);
  CHECK(text.find("launch/bricklayer camera-host --multicast-route eth0\n") != std::string::npos);
  CHECK(text.find("\nAmbientCapabilities=CAP_NET_ADMIN\n") != std::string::npos);
  CHECK(text.find("\nCapabilityBoundingSet=CAP_NET_ADMIN\n") != std::string::npos);

  // A camera host whose interface is called otherwise: --multicast-route overrides the profile's.
  harness::Ran renamed = setup({"--install-service", "camera-host", "--unit-dir", units.string(), "--user", user,
                                "--multicast-route", "enp3s0"});
  REQUIRE(renamed.status.clean());
  text = slurp(unit);
  CHECK(text.find("launch/bricklayer camera-host --multicast-route enp3s0\n") != std::string::npos);
  CHECK(text.find("eth0") == std::string::npos);
  if (auto v = verify(unit)) {
    INFO(v->out << v->err);
    CHECK(v->status.clean());
  }

  // The demo runs on one machine: no LAN, no capability, no route option.
  harness::Ran demo = setup({"--install-service", "demo", "--unit-dir", units.string(), "--user", user});
  REQUIRE(demo.status.clean());
  text = slurp(unit);
  CHECK(text.find("Capabilit") == std::string::npos);
  CHECK(text.find("--multicast-route") == std::string::npos);
  CHECK(text.find("launch/bricklayer demo\n") != std::string::npos);
  if (auto v = verify(unit)) {
    INFO(v->out << v->err);
    CHECK(v->status.clean());
  }

  harness::Ran removed = setup({"--remove-service", "--unit-dir", units.string()});
  CHECK(removed.status.clean());
  CHECK_FALSE(fs::exists(unit));
}

TEST_CASE("launch/setup refuses a service for a profile or user that does not exist") {
  harness::ScratchDir dir("service-bad");
  harness::Ran r = setup({"--install-service", "no-such-profile", "--unit-dir", dir.str()});
  CHECK(r.status.code == 2);
  CHECK(r.err.find("no profile 'no-such-profile'") != std::string::npos);
  harness::Ran u = setup({"--install-service", "demo", "--unit-dir", dir.str(), "--user", "no-such-user-here"});
  CHECK(u.status.code == 2);
  CHECK(u.err.find("no user 'no-such-user-here'") != std::string::npos);
  // Whatever --multicast-route says lands in ExecStart: only an interface name is taken.
  harness::Ran dev = setup({"--install-service", "camera-host", "--unit-dir", dir.str(), "--multicast-route", "eth0; rm"});
  CHECK(dev.status.code == 2);
  CHECK(dev.err.find("'eth0; rm' is not an interface name") != std::string::npos);
  CHECK_FALSE(fs::exists(dir / "bricklayer.service"));
}

TEST_CASE("systemd-analyze verify, as the test uses it, rejects a broken unit") {
  // Without this, a verify that accepted anything would make the check above worthless.
  harness::ScratchDir dir("service-verify");
  std::ofstream(dir / "broken.service") << "[Service]\nExecStart=relative/path\nRestart=sometimes\n";
  auto v = verify(dir / "broken.service");
  if (!v) {
    WARN("systemd-analyze is not installed");
    return;
  }
  CHECK_FALSE(v->status.clean());
}
