// The exporters' log source (the runtime's LogReader per file, chained) on logs written by LCM's own
// writer (lcm::LogFile), whole and damaged: a torn last event is reported as truncated, bytes that are
// no event as corrupt, every intact event around them is still read, and split files read in order.
#include <catch2/catch.hpp>

#include <lcm/lcm-cpp.hpp>

#include <filesystem>
#include <fstream>

#include "bricklayer/inspect/log_source.h"

using namespace bricklayer::inspect;
namespace fs = std::filesystem;

namespace {

fs::path temp_dir() {
  fs::path d = fs::path(BRICKLAYER_BINARY_DIR) / "test-output" / "inspect" / "log_source";
  fs::create_directories(d);
  return d;
}

// Ten events on two channels, payload i repeated i+1 times; returns each event's offset.
std::vector<uint64_t> write_log(const fs::path& path) {
  std::vector<uint64_t> offsets;
  lcm::LogFile log(path.string(), "w");
  REQUIRE(log.good());
  for (int i = 0; i < 10; ++i) {
    offsets.push_back(static_cast<uint64_t>(std::ftell(log.getFilePtr())));
    std::string channel = i % 2 ? "BL_ODD" : "BL_EVEN";
    std::vector<uint8_t> data(static_cast<size_t>(i + 1), static_cast<uint8_t>(i));
    lcm::LogEvent e{};
    e.eventnum = i;
    e.timestamp = 1000 + i;
    e.channel = channel;
    e.datalen = static_cast<int32_t>(data.size());
    e.data = data.data();
    REQUIRE(log.writeEvent(&e) == 0);
  }
  return offsets;
}

std::vector<LogEvent> read_all(LogSource& src) {
  std::vector<LogEvent> out;
  LogEvent e;
  while (src.next(e)) out.push_back(e);
  return out;
}

}  // namespace

TEST_CASE("a whole log is read event by event") {
  fs::path p = temp_dir() / "whole.lcmlog";
  write_log(p);
  LogSource src({p.string()});
  auto events = read_all(src);
  REQUIRE(events.size() == 10);
  CHECK(events[3].channel == "BL_ODD");
  CHECK(events[3].timestamp_us == 1003);
  CHECK(events[3].data == std::vector<uint8_t>(4, 3));
  CHECK(src.problems().empty());
  CHECK(src.bytes_read() == src.total_bytes());
}

TEST_CASE("a torn last event is reported as truncated, and the events before it are read") {
  fs::path p = temp_dir() / "torn.lcmlog";
  write_log(p);
  fs::resize_file(p, fs::file_size(p) - 3);
  LogSource src({p.string()});
  auto events = read_all(src);
  CHECK(events.size() == 9);
  REQUIRE(src.problems().size() == 1);
  CHECK(src.problems()[0].truncated);
  CHECK_THAT(src.problems()[0].what, Catch::Contains("truncated"));

  fs::path header_only = temp_dir() / "torn-header.lcmlog";
  auto offsets = write_log(header_only);
  fs::resize_file(header_only, offsets[9] + 10);
  LogSource src2({header_only.string()});
  CHECK(read_all(src2).size() == 9);
  REQUIRE(src2.problems().size() == 1);
  CHECK(src2.problems()[0].truncated);
  CHECK_THAT(src2.problems()[0].what, Catch::Contains("truncated"));
}

TEST_CASE("corrupt bytes in the middle are skipped to the next event and reported") {
  fs::path p = temp_dir() / "corrupt.lcmlog";
  auto offsets = write_log(p);
  {
    std::fstream f(p, std::ios::in | std::ios::out | std::ios::binary);
    f.seekp(static_cast<std::streamoff>(offsets[4]));  // the sync word of event 4
    f.write("XXXX", 4);
    f.seekp(static_cast<std::streamoff>(offsets[7] + 20));  // event 7's channel length: 2^31-1
    const char huge[4] = {0x7f, char(0xff), char(0xff), char(0xff)};
    f.write(huge, 4);
  }
  LogSource src({p.string()});
  auto events = read_all(src);
  std::vector<int64_t> numbers;
  for (const auto& e : events) numbers.push_back(e.number);
  CHECK(numbers == std::vector<int64_t>{0, 1, 2, 3, 5, 6, 8, 9});
  REQUIRE(src.problems().size() == 2);
  CHECK_FALSE(src.problems()[0].truncated);
  CHECK(src.problems()[0].offset == offsets[4]);
  CHECK_THAT(src.problems()[0].what, Catch::Contains("corrupt"));
  CHECK(src.problems()[1].offset == offsets[7]);
}

TEST_CASE("several files are read in order, and a missing one is an error at once") {
  fs::path a = temp_dir() / "split.00", b = temp_dir() / "split.01";
  write_log(a);
  write_log(b);
  LogSource src({a.string(), b.string()});
  auto events = read_all(src);
  REQUIRE(events.size() == 20);
  CHECK(events[10].file_index == 1);
  CHECK(events[10].number == 0);
  CHECK(src.bytes_read() == fs::file_size(a) + fs::file_size(b));
  CHECK_THROWS_AS(LogSource({a.string(), (temp_dir() / "absent").string()}), LogOpenError);
  std::ofstream(temp_dir() / "garbage") << "this is not a log at all";
  LogSource junk({(temp_dir() / "garbage").string()});
  CHECK(read_all(junk).empty());
  REQUIRE(junk.problems().size() == 1);
  CHECK(junk.problems()[0].offset == 0);
}
