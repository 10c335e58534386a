// NETNS: the clock check of two real bricklayer-doctor processes measuring each other from their
// heartbeats: the "other host" runs in a UTS namespace of its own (hostname peer-host) with its wall
// clock shifted by libfaketime (LD_PRELOAD; the package faketime), so the offset is known.
// The offset estimate itself is also checked on recorded heartbeat samples.
#include <catch2/catch.hpp>

#include <cstdlib>
#include <filesystem>
#include <regex>
#include <thread>

#include "bricklayer/doctor/clock_check.h"
#include "doctor_test_util.h"

using namespace bricklayer;
using test::check_line;
using test::severity;
namespace fs = std::filesystem;

namespace {
const std::string kUrl = "udpm://239.255.76.67:7667?ttl=0";
const std::string kFaketime = "/usr/lib/x86_64-linux-gnu/faketime/libfaketime.so.1";

// Another bricklayer-doctor on "peer-host", its clock shifted by `shift` (libfaketime's syntax:
// "-0.5" s), checking the clock for `listen_s` seconds: it publishes its own heartbeat meanwhile, as
// every doctor does, so the two measure each other.
std::vector<std::string> peer_doctor(const std::string& shift, const std::string& listen_s) {
  std::string script = "hostname peer-host && ";
  // An AddressSanitizer build insists on coming first among the libraries; libfaketime must (it
  // replaces clock_gettime), so the order check is off for the peer alone.
  if (!shift.empty())
    script += "export FAKETIME='" + shift + "' LD_PRELOAD=" + kFaketime +
              " ASAN_OPTIONS=\"${ASAN_OPTIONS:-}:verify_asan_link_order=0\" && ";
  script += "exec \"$0\" \"$@\"";
  return {"/usr/bin/unshare", getuid() == 0 ? "-u" : "-ru", "sh", "-c", script, harness::program_path("bricklayer-doctor"),
          "projector-host", "--checks", "clock", "--lcm-url", kUrl, "--listen-s", listen_s};
}

// Both doctors at once; returns (ours, the peer's).
std::pair<test::DoctorRun, test::DoctorRun> both(const std::string& profile, const std::string& shift) {
  test::DoctorRun peer;
  std::thread t([&] { peer = test::run_capture(peer_doctor(shift, "4")); });
  usleep(300000);  // the peer's first heartbeat goes out as it starts
  test::DoctorRun ours = test::run_doctor({profile, "--checks", "clock", "--lcm-url", kUrl, "--listen-s", "3"});
  t.join();
  return {ours, peer};
}

double offset_in(const std::string& line, const std::string& host = "peer-host") {
  std::smatch m;
  if (!std::regex_search(line, m, std::regex(host + " is ([0-9.]+) ms (behind|ahead)"))) return 1e9;
  return std::stod(m[1]) * (m[2] == "behind" ? 1 : -1);
}
}  // namespace

TEST_CASE("a peer whose clock is 500 ms behind: each doctor measures the other from its heartbeats and warns") {
  REQUIRE(fs::exists(kFaketime));
  auto [r, peer] = both("camera-host", "-0.5");
  INFO(r.out);
  INFO("peer: " << peer.out);
  const std::string line = check_line(r.out, "clock");
  CHECK(severity(line) == "warning");
  CHECK(offset_in(line) == Approx(500).margin(40));
  CHECK(line.find("fix: run NTP on both hosts") != std::string::npos);
  CHECK(r.code == 0);  // no module compares clocks: a warning, not a failure
  // The peer sees this host 500 ms ahead.
  CHECK(offset_in(check_line(peer.out, "clock"), doctor::own_host_name()) == Approx(-500).margin(40));
}

TEST_CASE("a peer 300 ms ahead, and one on the same clock") {
  auto ahead = both("camera-host", "+0.3");
  INFO(ahead.first.out);
  CHECK(offset_in(check_line(ahead.first.out, "clock")) == Approx(-300).margin(40));
  auto same = both("projector-host", "");
  INFO(same.first.out);
  const std::string line = check_line(same.first.out, "clock");
  CHECK(severity(line) == "ok");
  CHECK(std::abs(offset_in(line)) < doctor::kClockWarningMs);
}

TEST_CASE("no other host heard: a warning saying what to start, one host: nothing to check") {
  auto r = test::run_doctor({"camera-host", "--checks", "clock", "--lcm-url", kUrl, "--listen-s", "1.5"});
  INFO(r.out);
  CHECK(check_line(r.out, "clock").find("warning  clock                no heartbeat from another host in 2 s") == 0);
  r = test::run_doctor({"demo", "--checks", "clock", "--lcm-url", kUrl});
  CHECK(check_line(r.out, "clock").find("ok       clock                one host") == 0);
}

TEST_CASE("offsets from recorded heartbeats: the smallest difference per host, own host ignored") {
  std::vector<doctor::HeartbeatSample> samples = {
      {"prediction", "peer:10", 1'000'000, 1'250'400},  // 250.4 ms: offset + 0.4 ms delay
      {"projection", "peer:11", 2'000'000, 2'250'200},  // the fastest: 250.2
      {"prediction", "peer:10", 3'000'000, 3'253'000},  // a slow one
      {"vision", "here:5", 1'000'000, 9'000'000},       // our own host: not a peer
      {"logger", "far:7", 5'000'000, 4'990'000},        // 10 ms ahead
  };
  auto peers = doctor::estimate_offsets(samples, "here");
  REQUIRE(peers.size() == 2);
  CHECK(peers[0].host == "far");
  CHECK(peers[0].offset_ms == Approx(-10));
  CHECK(peers[1].host == "peer");
  CHECK(peers[1].offset_ms == Approx(250.2));
  CHECK(peers[1].spread_ms == Approx(2.8));
  CHECK(peers[1].samples == 3);
  doctor::HostPlan plan;
  plan.two_hosts = true;
  CHECK(doctor::judge_clock(plan, peers, 3).severity == doctor::Severity::kWarning);
  CHECK(doctor::judge_clock(plan, {{"peer", 0.3, 0.1, 3}}, 3).severity == doctor::Severity::kOk);
}
