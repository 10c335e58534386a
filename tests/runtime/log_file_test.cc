#include <catch2/catch.hpp>

#include <lcm/lcm-cpp.hpp>

#include <string>
#include <vector>

#include "bricklayer/runtime/log_file.h"
#include "harness/scratch.h"

using namespace bricklayer::runtime;
using bricklayer::harness::read_file;
using bricklayer::harness::ScratchDir;
using bricklayer::harness::write_file;

namespace {
std::string event_bytes(int64_t number, int64_t utime, const std::string& channel, const std::string& data) {
  const auto e = encode_log_event(number, utime, channel, reinterpret_cast<const uint8_t*>(data.data()), data.size());
  return std::string(e.begin(), e.end());
}

struct Read {
  std::vector<std::string> events;  // "channel=data@utime"
  std::vector<LogDamage> damage;
};
Read read_all(const std::string& path) {
  LogReader reader(path);
  Read out;
  LogEvent e;
  while (reader.next(e)) out.events.push_back(e.channel + "=" + std::string(e.data.begin(), e.data.end()) + "@" + std::to_string(e.utime));
  out.damage = reader.damage();
  return out;
}
}  // namespace

TEST_CASE("LogWriter writes standard LCM logs that lcm::LogFile reads, and LogReader reads lcm::LogFile's") {
  ScratchDir dir("logfile");
  const std::string ours = (dir / "ours.lcmlog").string();
  {
    LogWriter w(ours);
    const std::string a = "hello", b = "";
    REQUIRE(w.write(100, "BL_A", reinterpret_cast<const uint8_t*>(a.data()), a.size()));
    REQUIRE(w.write(200, "BL_B", reinterpret_cast<const uint8_t*>(b.data()), b.size()));
    CHECK(w.events() == 2);
    CHECK(w.bytes() == 28 + 4 + 5 + 28 + 4);
    REQUIRE(w.flush());
  }
  {
    lcm::LogFile lf(ours, "r");
    REQUIRE(lf.good());
    const lcm::LogEvent* e = lf.readNextEvent();
    REQUIRE(e);
    CHECK(e->channel == "BL_A");
    CHECK(e->timestamp == 100);
    CHECK(std::string(static_cast<const char*>(e->data), e->datalen) == "hello");
    e = lf.readNextEvent();
    REQUIRE(e);
    CHECK(e->channel == "BL_B");
    CHECK(e->eventnum == 1);
    CHECK(lf.readNextEvent() == nullptr);
  }
  const std::string theirs = (dir / "theirs.lcmlog").string();
  {
    lcm::LogFile lf(theirs, "w");
    std::string payload = "xyz";
    lcm::LogEvent e{};
    e.eventnum = 0;
    e.timestamp = 777;
    e.channel = "BL_C";
    e.datalen = 3;
    e.data = payload.data();
    REQUIRE(lf.writeEvent(&e) == 0);
  }
  const Read r = read_all(theirs);
  CHECK(r.events == std::vector<std::string>{"BL_C=xyz@777"});
  CHECK(r.damage.empty());
}

TEST_CASE("a torn event in the middle is reported, and every intact event after it is still read") {
  ScratchDir dir("logfile");
  const std::string b = event_bytes(1, 20, "BL_B", std::string(100, 'b'));
  write_file(dir / "torn.lcmlog", event_bytes(0, 10, "BL_A", "a") + b.substr(0, 60) + event_bytes(2, 30, "BL_C", "c") +
                                      event_bytes(3, 40, "BL_D", "d"));
  const Read r = read_all((dir / "torn.lcmlog").string());
  CHECK(r.events == std::vector<std::string>{"BL_A=a@10", "BL_C=c@30", "BL_D=d@40"});
  REQUIRE(r.damage.size() == 1);
  CHECK(r.damage[0].offset == 28 + 4 + 1);
  CHECK(r.damage[0].bytes == 60);
  CHECK_FALSE(r.damage[0].at_end);
  CHECK(r.damage[0].describe().find("torn") != std::string::npos);
}

TEST_CASE("a log that ends inside an event is reported as truncated") {
  ScratchDir dir("logfile");
  const std::string c = event_bytes(2, 30, "BL_C", "ccccccccc");
  write_file(dir / "cut.lcmlog", event_bytes(0, 10, "BL_A", "a") + event_bytes(1, 20, "BL_B", "b") + c.substr(0, c.size() - 3));
  const Read r = read_all((dir / "cut.lcmlog").string());
  CHECK(r.events == std::vector<std::string>{"BL_A=a@10", "BL_B=b@20"});
  REQUIRE(r.damage.size() == 1);
  CHECK(r.damage[0].at_end);
  CHECK(r.damage[0].bytes == static_cast<int64_t>(c.size() - 3));
  CHECK(r.damage[0].describe().find("truncated") != std::string::npos);
}

TEST_CASE("garbage before, between and after events is skipped and reported, a clean log has no damage") {
  ScratchDir dir("logfile");
  write_file(dir / "junk.lcmlog", std::string("\xED\xA1junk", 6) + event_bytes(0, 10, "BL_A", "a") + "zz" +
                                      event_bytes(1, 20, "BL_B", "b") + "x");
  const Read r = read_all((dir / "junk.lcmlog").string());
  CHECK(r.events == std::vector<std::string>{"BL_A=a@10", "BL_B=b@20"});
  REQUIRE(r.damage.size() == 3);
  // Every byte is in an event or in a reported region.
  CHECK(r.damage[0].bytes + 33 + r.damage[1].bytes + 33 + r.damage[2].bytes == 6 + 33 + 2 + 33 + 1);
  write_file(dir / "clean.lcmlog", event_bytes(0, 10, "BL_A", "a"));
  CHECK(read_all((dir / "clean.lcmlog").string()).damage.empty());
  write_file(dir / "empty.lcmlog", "");
  CHECK(read_all((dir / "empty.lcmlog").string()).events.empty());
  CHECK_THROWS_AS(LogReader((dir / "missing.lcmlog").string()), std::runtime_error);
}

TEST_CASE("seek continues at an event's offset") {
  ScratchDir dir("logfile");
  const std::string a = event_bytes(0, 10, "BL_A", "a");
  write_file(dir / "s.lcmlog", a + event_bytes(1, 20, "BL_B", "b"));
  LogReader reader((dir / "s.lcmlog").string());
  reader.seek(static_cast<int64_t>(a.size()));
  LogEvent e;
  REQUIRE(reader.next(e));
  CHECK(e.channel == "BL_B");
  CHECK(e.offset == static_cast<int64_t>(a.size()));
  CHECK_FALSE(reader.next(e));
  CHECK(reader.position() == reader.size());
}
