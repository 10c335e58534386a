// NETNS: the bus checks of the real bricklayer-doctor in a private network namespace: with the
// multicast route on loopback (run-in-netns adds it), without it, with multicast off, with a LAN URL
// whose route goes through lo or through a veth, and the receive buffers against net.core.rmem_max.
#include <catch2/catch.hpp>

#include <cstdlib>
#include <fstream>

#include "bricklayer/doctor/bus_checks.h"
#include "doctor_test_util.h"

using namespace bricklayer;
using test::check_line;
using test::run_doctor;
using test::severity;

namespace {
const std::string kHostOnly = "udpm://239.255.76.67:7667?ttl=0";
const std::string kLan = "udpm://239.255.76.67:7667?ttl=1";
int sh(const std::string& cmd) { return std::system(cmd.c_str()); }
int64_t rmem_max() {
  int64_t v = -1;
  std::ifstream("/proc/sys/net/core/rmem_max") >> v;
  return v;
}
}  // namespace

TEST_CASE("with the route on loopback: route ok via lo, a message comes back, exit 0") {
  auto r = run_doctor({"demo", "--checks", "bus", "--lcm-url", kHostOnly});
  INFO(r.out);
  CHECK(r.code == 0);
  CHECK(severity(check_line(r.out, "bus url")) == "ok");
  CHECK(check_line(r.out, "multicast route").find("ok       multicast route      239.255.76.67 leaves via lo") == 0);
  CHECK(severity(check_line(r.out, "bus loopback")) == "ok");
  CHECK(check_line(r.out, "bus loopback").find("came back in") != std::string::npos);
  CHECK(severity(check_line(r.out, "receive buffers")) == "ok");
}

TEST_CASE("without a multicast route: route and loopback fail with the command that fixes them") {
  REQUIRE(sh("ip route del 224.0.0.0/4 dev lo") == 0);
  auto r = run_doctor({"demo", "--checks", "bus", "--lcm-url", kHostOnly});
  INFO(r.out);
  CHECK(r.code == 1);
  const std::string route = check_line(r.out, "multicast route");
  CHECK(severity(route) == "FAILED");
  CHECK(route.find("no route to 239.255.76.67") != std::string::npos);
  CHECK(route.find("fix: sudo ip route add 224.0.0.0/4 dev lo") != std::string::npos);
  CHECK(severity(check_line(r.out, "bus loopback")) == "FAILED");
  // The fix works.
  REQUIRE(sh("ip route add 224.0.0.0/4 dev lo") == 0);
  CHECK(run_doctor({"demo", "--checks", "bus", "--lcm-url", kHostOnly}).code == 0);
}

TEST_CASE("multicast off: a warning on lo (messages still loop back), a failure on the LAN interface") {
  REQUIRE(sh("ip link set lo multicast off") == 0);
  auto r = run_doctor({"demo", "--checks", "bus", "--lcm-url", kHostOnly});
  INFO(r.out);
  const std::string route = check_line(r.out, "multicast route");
  CHECK(severity(route) == "warning");
  CHECK(route.find("multicast off -- fix: sudo ip link set lo multicast on") != std::string::npos);
  CHECK(severity(check_line(r.out, "bus loopback")) == "ok");
  CHECK(r.code == 0);
  sh("ip link set lo multicast on");
  REQUIRE(sh("ip link add bldoc2 type veth peer name bldoc3 && ip addr add 10.231.1.1/24 dev bldoc2 && "
             "ip link set bldoc2 multicast off && ip link set bldoc2 up && ip link set bldoc3 up && "
             "ip route replace 224.0.0.0/4 dev bldoc2") == 0);
  r = run_doctor({"camera-host", "--checks", "bus", "--lcm-url", kLan});
  INFO(r.out);
  CHECK(check_line(r.out, "multicast route").find("FAILED   multicast route      239.255.76.67 leaves via bldoc2 (10.231.1.1), which has multicast off") == 0);
  CHECK(r.code == 1);
}

TEST_CASE("one of two hosts: ttl=0 fails, a LAN route through lo fails, a route through a real link is ok") {
  auto r = run_doctor({"camera-host", "--checks", "bus", "--lcm-url", kHostOnly});
  INFO(r.out);
  CHECK(r.code == 1);
  CHECK(check_line(r.out, "bus url").find("ttl=0 never leaves this host") != std::string::npos);

  r = run_doctor({"camera-host", "--checks", "bus", "--lcm-url", kLan});
  INFO(r.out);
  CHECK(severity(check_line(r.out, "bus url")) == "ok");
  CHECK(check_line(r.out, "multicast route").find("the other host will not hear it") != std::string::npos);
  CHECK(r.code == 1);

  // A veth pair inside this test's own namespace stands for the LAN interface.
  REQUIRE(sh("ip link add bldoc0 type veth peer name bldoc1 && ip addr add 10.231.0.1/24 dev bldoc0 && "
             "ip link set bldoc0 up && ip link set bldoc1 up && ip route replace 224.0.0.0/4 dev bldoc0") == 0);
  r = run_doctor({"camera-host", "--checks", "bus", "--lcm-url", kLan + "&recv_buf_size=65536"});
  INFO(r.out);
  CHECK(check_line(r.out, "multicast route").find("ok       multicast route      239.255.76.67 leaves via bldoc0 (10.231.0.1)") == 0);
  CHECK(severity(check_line(r.out, "bus loopback")) == "ok");  // multicast loops back to this host on any interface
  CHECK(severity(check_line(r.out, "receive buffers")) == "ok");
  CHECK(r.code == 0);
}

TEST_CASE("receive buffers: what the URL asks for against what the kernel grants under net.core.rmem_max") {
  const int64_t cap = rmem_max();
  REQUIRE(cap > 4096);
  const std::string below = kLan + "&recv_buf_size=" + std::to_string(cap / 2);
  const std::string above = kLan + "&recv_buf_size=" + std::to_string(cap * 2);
  doctor::HostPlan plan;
  plan.lcm_url = below;
  auto ok = doctor::check_receive_buffers(plan);
  INFO(ok.detail);
  CHECK(ok.severity == doctor::Severity::kOk);
  plan.lcm_url = above;
  auto capped = doctor::check_receive_buffers(plan);
  INFO(capped.detail);
  CHECK(capped.severity == doctor::Severity::kWarning);
  CHECK(capped.fix.find("sudo sysctl -w net.core.rmem_max=") == 0);
  // A LAN URL that asks for nothing: a warning either way (small cap, or the URL should ask).
  plan.lcm_url = kLan;
  CHECK(doctor::check_receive_buffers(plan).severity == doctor::Severity::kWarning);
  // One host: no larger buffer needed.
  plan.lcm_url = kHostOnly;
  CHECK(doctor::check_receive_buffers(plan).severity == doctor::Severity::kOk);
}

TEST_CASE("udpm URLs are read as LCM reads them") {
  auto u = doctor::parse_udpm_url("udpm://239.1.2.3:7000?ttl=0&recv_buf_size=100&ttl=1");
  REQUIRE(u);
  CHECK(u->group == "239.1.2.3");
  CHECK(u->port == 7000);
  CHECK(u->ttl == 1);  // the last one counts
  CHECK(u->recv_buf_size == 100);
  CHECK_FALSE(doctor::parse_udpm_url("memq://"));
  CHECK_THROWS_AS(doctor::parse_udpm_url("udpm://10.0.0.1:7667?ttl=0"), std::invalid_argument);
  CHECK_THROWS_AS(doctor::parse_udpm_url("udpm://239.1.2.3:7667?ttl=5"), std::invalid_argument);
}
