// bricklayer-logger on a small real file system (a tmpfs mounted in this test's own mount namespace,
// the bus in its own network namespace: run-in-own-mounts), with bricklayer-prediction running beside
// it as the rest of the exhibit:
// - within its budget it keeps the newest data, deleting the oldest files, and never exceeds it;
// - on a full disk it keeps running, counts what it could not keep, leaves no torn event, notes the
//   loss in the index, and writes into a new file once space returns; what it counts as written is
//   exactly what the files hold; prediction answers stacks the whole time.
#include <catch2/catch.hpp>

#include <sys/mount.h>

#include <algorithm>
#include <filesystem>
#include <map>
#include <thread>

#include "bricklayer/common/channels.h"
#include "bricklayer/logger/recording_index.h"
#include "bricklayer/prediction/sample_stacks.h"
#include "bricklayer/prediction_t.hpp"
#include "bricklayer/runtime/lcm_bus.h"
#include "bricklayer/runtime/log_file.h"
#include "harness/program.h"
#include "harness/recorder.h"
#include "harness/scratch.h"

using namespace bricklayer;
using namespace std::chrono_literals;
namespace fs = std::filesystem;

namespace {
const std::string kUrl = "udpm://239.255.76.67:7667?ttl=0";
const std::string kData = "TEST_DATA";

struct SmallDisk {
  harness::ScratchDir dir{"logger-small-disk"};
  fs::path mnt = dir / "mnt";
  explicit SmallDisk(const std::string& size) {
    fs::create_directories(mnt);
    REQUIRE(::mount("bricklayer-logger-test", mnt.c_str(), "tmpfs", 0, ("size=" + size).c_str()) == 0);
  }
  ~SmallDisk() { ::umount2(mnt.c_str(), MNT_DETACH); }
  // Bytes of the recording's files (parts and index).
  int64_t series_bytes(const std::string& prefix) const {
    int64_t n = 0;
    // The logger deletes old parts while this runs: a file gone between the listing and its size counts 0.
    std::error_code ec;
    for (const auto& e : fs::directory_iterator(mnt, ec)) {
      if (e.path().filename().string().rfind(prefix, 0) != 0) continue;
      const auto size = fs::file_size(e.path(), ec);
      if (!ec) n += static_cast<int64_t>(size);
    }
    return n;
  }
  std::vector<fs::path> parts(const std::string& prefix) const {
    std::vector<fs::path> out;
    for (const auto& e : fs::directory_iterator(mnt)) {
      const std::string name = e.path().filename().string();
      if (name.rfind(prefix, 0) == 0 && e.path().extension() != ".index") out.push_back(e.path());
    }
    // By number: .100 comes after .99.
    std::sort(out.begin(), out.end(), [](const fs::path& a, const fs::path& b) {
      return std::stoi(a.extension().string().substr(1)) < std::stoi(b.extension().string().substr(1));
    });
    return out;
  }
};

std::vector<uint8_t> numbered(uint32_t i, size_t size) {
  std::vector<uint8_t> d(size, static_cast<uint8_t>(i));
  for (int b = 0; b < 4; ++b) d[static_cast<size_t>(b)] = static_cast<uint8_t>(i >> (8 * b));
  return d;
}
uint32_t number_of(const std::vector<uint8_t>& d) {
  return d[0] | d[1] << 8 | d[2] << 16 | static_cast<uint32_t>(d[3]) << 24;
}

struct ReadBack {
  int64_t events = 0, bytes = 0;
  bool damaged = false;
  std::vector<uint32_t> data;  // numbers of the TEST_DATA messages, in file order
};
ReadBack read_parts(const std::vector<fs::path>& parts) {
  ReadBack r;
  for (const auto& p : parts) {
    runtime::LogReader reader(p.string());
    runtime::LogEvent e;
    while (reader.next(e)) {
      ++r.events;
      if (e.channel == kData) r.data.push_back(number_of(e.data));
    }
    r.damaged = r.damaged || !reader.damage().empty();
    r.bytes += reader.size();
  }
  return r;
}

double value(const heartbeat_t& hb, const std::string& name) { return harness::heartbeat_value(hb, name).value_or(-1); }
}  // namespace

TEST_CASE("within its budget the logger keeps the newest data and never exceeds the budget") {
  SmallDisk disk("8m");
  runtime::LcmBus bus(kUrl);
  auto rec = harness::Recorder::live(bus, {channel(kHeartbeatChannel)});
  harness::Program logger("bricklayer-logger", {"--lcm-url=" + kUrl, "--budget-mb", "2", "--split-mb", "0.25", "--series",
                                                "rec-", "--flush-ms", "20", (disk.mnt / "rec-1").string()});
  REQUIRE(rec.wait_for_heartbeat("logger", {}, 10s));
  int64_t most = 0;
  for (uint32_t i = 0; i < 400; ++i) {  // 8 MB through a 2 MB budget
    const auto d = numbered(i, 20000);
    REQUIRE(bus.publish(kData, d.data(), d.size()));
    if (i % 10 == 0) {
      most = std::max(most, disk.series_bytes("rec-"));
      rec.pump_for(5ms);
    }
  }
  REQUIRE(rec.wait_for_heartbeat("logger", [](const heartbeat_t& hb) {
    return value(hb, "queue_bytes") == 0 && hb.published >= 400 && value(hb, "held_bytes") == 0;
  }, 20s));
  most = std::max(most, disk.series_bytes("rec-"));
  const auto status = logger.stop();
  INFO(logger.stderr_text());
  CHECK(status.clean());
  CHECK(most <= 2 << 20);
  CHECK(disk.series_bytes("rec-") <= 2 << 20);
  const heartbeat_t hb = *rec.last_heartbeat("logger");
  CHECK(value(hb, "deleted_files") >= 20);
  CHECK(value(hb, "lost") == 0);
  // What is kept is a contiguous run ending with the newest message.
  const ReadBack back = read_parts(disk.parts("rec-1."));
  CHECK_FALSE(back.damaged);
  REQUIRE(back.data.size() > 60);
  CHECK(back.data.back() == 399);
  for (size_t k = 1; k < back.data.size(); ++k) CHECK(back.data[k] == back.data[k - 1] + 1);
  // Its index seeks into parts that still exist for recent times.
  const auto index = logger::RecordingIndex::load((disk.mnt / "rec-1.index").string());
  const auto seek = index.seek(INT64_MAX);
  REQUIRE(seek);
  CHECK(fs::exists(seek->part));
}

TEST_CASE("a full disk is counted, never torn, the exhibit goes on, and the logger writes again once space returns") {
  SmallDisk disk("2m");
  harness::write_file(disk.mnt / "filler", std::string(1500 * 1024, 'f'));  // someone else's 1.5 MB
  runtime::LcmBus bus(kUrl);
  auto rec = harness::Recorder::live(bus, {channel(kHeartbeatChannel), channel(kPredictionChannel)});
  harness::Program prediction("bricklayer-prediction", {"--lcm-url=" + kUrl});
  harness::Program logger("bricklayer-logger", {"--lcm-url=" + kUrl, "--flush-ms", "20", (disk.mnt / "rec").string()});
  REQUIRE(rec.wait_for_heartbeat("logger", {}, 10s));
  REQUIRE(rec.wait_for_heartbeat("prediction", {}, 10s));
  int64_t frame = 0;
  auto send = [&](uint32_t from, uint32_t to) {
    for (uint32_t i = from; i < to; ++i) {
      const auto d = numbered(i, 20000);
      REQUIRE(bus.publish(kData, d.data(), d.size()));
      const auto s = runtime::encode(prediction::sample_stack(6, static_cast<uint32_t>(frame), bus.now_utime(), frame));
      ++frame;
      REQUIRE(bus.publish(channel(kStackChannel), s.data(), s.size()));
      rec.pump_for(3ms);
    }
  };
  send(0, 100);  // 2 MB into about 0.5 MB of room
  REQUIRE(rec.wait_for_heartbeat("logger", [](const heartbeat_t& hb) { return value(hb, "lost") > 0; }, 10s));
  const heartbeat_t full = *rec.last_heartbeat("logger");
  CHECK(full.status.rfind("LOSING", 0) == 0);
  CHECK(full.status.find("not kept") != std::string::npos);
  // The rest of the exhibit: prediction answered the stacks sent while the disk was full.
  const int64_t last_frame = frame - 1;
  CHECK(rec.wait_for<prediction_t>(channel(kPredictionChannel),
                                   [&](const prediction_t& p) { return p.frame_number == last_frame; }, 5s));
  CHECK(prediction.running());
  // Space returns.
  fs::remove(disk.mnt / "filler");
  send(100, 150);
  REQUIRE(rec.wait_for_heartbeat("logger", [](const heartbeat_t& hb) {
    return value(hb, "files") >= 2 && value(hb, "queue_bytes") == 0 && hb.published > 0;
  }, 10s));
  rec.pump_for(300ms);
  const auto status = logger.stop();
  INFO(logger.stderr_text());
  CHECK(status.clean());
  rec.pump_for(200ms);
  const heartbeat_t last = *rec.last_heartbeat("logger");

  const auto parts = disk.parts("rec.");
  REQUIRE(parts.size() >= 2);
  const ReadBack back = read_parts(parts);
  CHECK_FALSE(back.damaged);  // the torn event was cut off, nothing was appended behind it
  // Written is what the files hold, exactly.
  CHECK(back.events == last.published);
  CHECK(back.bytes == static_cast<int64_t>(value(last, "bytes_written")));
  // The first part holds the start, contiguous, up to the loss; the newest messages are after it.
  REQUIRE(!back.data.empty());
  CHECK(back.data.front() == 0);
  size_t k = 1;
  while (k < back.data.size() && back.data[k] == back.data[k - 1] + 1) ++k;
  CHECK(k < back.data.size());  // a gap: the loss
  CHECK(back.data.back() == 149);
  CHECK(value(last, "lost") > 0);
  // The loss is in the index, with every event not kept.
  const auto index = logger::RecordingIndex::load((disk.mnt / "rec.index").string());
  int64_t noted = 0;
  for (const auto& l : index.losses()) noted += l.events;
  CHECK(noted == static_cast<int64_t>(value(last, "lost")));
  CHECK(prediction.running());
  // Replaying the recording reports the loss and fails, whatever the mismatches: from its index, and
  // from its parts alone (the logger's heartbeats in them carry the loss).
  std::vector<std::string> part_names;
  for (const auto& p : parts) part_names.push_back(p.string());
  for (const auto& sources : {std::vector<std::string>{(disk.mnt / "rec.index").string()}, part_names}) {
    std::vector<std::string> args = sources;
    args.insert(args.end(), {"--check", "--no-progress"});
    const auto r = harness::run_program("bricklayer-replay", args, 60s);
    INFO(sources.front() << "\n" << r.out << r.err);
    CHECK(r.status.code == 3);
    CHECK(r.out.find("DAMAGED ") != std::string::npos);
    CHECK(r.out.find("could not keep") != std::string::npos);
    CHECK(r.out.find("THE LOG IS DAMAGED OR INCOMPLETE") != std::string::npos);
  }
}
