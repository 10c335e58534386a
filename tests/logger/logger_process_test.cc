// NETNS, real processes over the real bus: bricklayer-logger records everything published at full
// rate on several channels (big fragmented camera frames included) exactly once, in order per
// channel, byte-identical; rotates and splits like lcm-logger; writes everything on SIGTERM; starts a
// new file on SIGHUP; leaves out what --exclude names; reports the losses it can see (frame-number
// gaps, a full kernel buffer); and refuses bad arguments with a clear error.
#include <catch2/catch.hpp>

#include <lcm/lcm-cpp.hpp>
#include <signal.h>
#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <map>
#include <memory>
#include <numeric>

#include "bricklayer/common/channels.h"
#include "bricklayer/heartbeat_t.hpp"
#include "bricklayer/image_t.hpp"
#include "bricklayer/runtime/codec.h"
#include "bricklayer/runtime/lcm_bus.h"
#include "harness/live_bus.h"
#include "harness/program.h"
#include "harness/recorder.h"
#include "harness/scratch.h"

using namespace bricklayer;
using namespace std::chrono_literals;
namespace fs = std::filesystem;

namespace {

using harness::ScratchDir;

double value_of(const heartbeat_t& hb, const std::string& name) { return harness::heartbeat_value(hb, name).value_or(-1); }

// A bricklayer-logger process and a view of its heartbeats.
class LoggerUnderTest {
 public:
  explicit LoggerUnderTest(std::vector<std::string> args) {
    args.insert(args.begin(), {"--lcm-url", harness::kLiveUrl});
    proc_ = std::make_unique<harness::Program>("bricklayer-logger", std::move(args));
    // Subscribed once it beats: from then on nothing may be missed.
    REQUIRE(wait_heartbeat([](const heartbeat_t&) { return true; }, 10s));
  }
  // Pumps until the newest heartbeat of this process satisfies pred.
  bool wait_heartbeat(const std::function<bool(const heartbeat_t&)>& pred, std::chrono::milliseconds timeout) {
    return rec_.wait_until([&] { return last_ok() && pred(last_); }, timeout);
  }
  const heartbeat_t& last() {
    last_ok();
    return last_;
  }
  harness::Program& proc() { return *proc_; }
  // SIGTERM; the exit status (the test fails when it needs SIGKILL).
  launcher::ExitStatus stop() {
    proc_->signal(SIGTERM);
    auto st = proc_->wait_exit(10s);
    REQUIRE(st);
    return *st;
  }
  std::string stderr_text() const { return proc_->stderr_text(); }

 private:
  bool last_ok() {
    const auto& messages = rec_.messages();
    for (auto it = messages.rbegin(); it != messages.rend(); ++it) {
      const auto hb = runtime::decode<heartbeat_t>(it->bytes);
      if (hb && hb->module == "logger" && hb->pid == proc_->pid()) {
        last_ = *hb;
        return true;
      }
    }
    return false;
  }
  runtime::LcmBus bus_{harness::kLiveUrl};
  harness::Recorder rec_ = harness::Recorder::live(bus_, {channel(kHeartbeatChannel)});
  std::unique_ptr<harness::Program> proc_;
  heartbeat_t last_{};
};

struct Logged {
  std::string channel;
  std::vector<uint8_t> data;
};
std::vector<Logged> read_log(const fs::path& p) {
  std::vector<Logged> out;
  auto log = std::make_unique<lcm::LogFile>(p.string(), "r");
  REQUIRE(log->good());
  while (const lcm::LogEvent* e = log->readNextEvent()) {
    const auto* b = static_cast<const uint8_t*>(e->data);
    out.push_back({e->channel, std::vector<uint8_t>(b, b + e->datalen)});
  }
  return out;
}
std::vector<Logged> only(const std::vector<Logged>& all, const std::string& ch) {
  std::vector<Logged> out;
  std::copy_if(all.begin(), all.end(), std::back_inserter(out), [&](const Logged& l) { return l.channel == ch; });
  return out;
}

// n bytes, the first four the message's index, the rest a deterministic function of (index, channel).
std::vector<uint8_t> payload(uint32_t i, const std::string& ch, size_t n) {
  std::vector<uint8_t> d(std::max<size_t>(n, 4));
  for (size_t k = 0; k < d.size(); ++k) d[k] = static_cast<uint8_t>((i * 2654435761u + k * 40503u + ch[0]) >> 13);
  d[0] = i & 0xff, d[1] = (i >> 8) & 0xff, d[2] = (i >> 16) & 0xff, d[3] = (i >> 24) & 0xff;
  return d;
}

image_t frame(int64_t number, size_t bytes, const std::string& source = "test-camera") {
  image_t img{};
  img.utime = 1000 + number;
  img.frame_number = number;
  img.width = 640;
  img.height = 480;
  img.format = image_t::FORMAT_JPEG;
  img.source = source;
  img.data = payload(static_cast<uint32_t>(number), "I", bytes);
  img.size = static_cast<int32_t>(img.data.size());
  return img;
}

int run_logger_expecting_exit(std::vector<std::string> args, std::string& err) {
  args.insert(args.begin(), {"--lcm-url", harness::kLiveUrl});
  const harness::Ran ran = harness::run_program("bricklayer-logger", std::move(args), 10s);
  REQUIRE_FALSE(ran.timed_out);
  err = ran.err;
  return ran.status.signal ? -ran.status.signal : ran.status.code;
}

// The test's publisher on the live bus.
struct Publisher {
  runtime::LcmBus bus{harness::kLiveUrl};
  bool raw(const std::string& ch, const std::vector<uint8_t>& data) { return harness::publish_bytes(bus, ch, data); }
  template <typename T>
  bool typed(const std::string& ch, const T& msg) {
    return harness::publish(bus, ch, msg);
  }
};

}  // namespace

TEST_CASE("everything published at full rate on several channels is logged exactly once, in order, byte-identical") {
  ScratchDir dir("full-rate");
  LoggerUnderTest logger({(dir / "log").string()});
  Publisher pub;
  REQUIRE(pub.bus.open());

  // 3000 messages round-robin on three channels (64 B, 1 KB, 8 KB) and a 150 KB camera frame (three
  // 64 KB fragments, each lost whole if one piece is) after every 30th: ~24 MB as fast as LCM sends.
  const std::vector<std::pair<std::string, size_t>> channels = {{"TEST_SMALL", 64}, {"TEST_MEDIUM", 1024}, {"TEST_LARGE", 8192}};
  std::map<std::string, std::vector<std::vector<uint8_t>>> sent;
  const std::string image_channel = channel(kImageChannel);
  int64_t frames = 0;
  for (uint32_t i = 0; i < 3000; ++i) {
    const auto& [ch, size] = channels[i % channels.size()];
    auto data = payload(i, ch, size);
    REQUIRE(pub.raw(ch, data));
    sent[ch].push_back(std::move(data));
    if (i % 30 == 0) {
      image_t img = frame(frames++, 150000);
      REQUIRE(pub.typed(image_channel, img));
      sent[image_channel].push_back(runtime::encode(img));
    }
  }
  const int64_t total = 3000 + frames;
  REQUIRE(logger.wait_heartbeat([&](const heartbeat_t& hb) { return hb.received >= total; }, 30s));
  const launcher::ExitStatus st = logger.stop();
  INFO(logger.stderr_text());
  CHECK(st.clean());

  REQUIRE(fs::exists(dir / "log.00"));
  CHECK_FALSE(fs::exists(dir / "log.01"));
  const auto logged = read_log(dir / "log.00");
  for (const auto& [ch, msgs] : sent) {
    INFO("channel " << ch);
    const auto got = only(logged, ch);
    REQUIRE(got.size() == msgs.size());
    for (size_t k = 0; k < msgs.size(); ++k) {
      if (got[k].data != msgs[k]) FAIL("message " << k << " differs (or is out of order)");
    }
  }
  // Its own account agrees: nothing lost anywhere it can see.
  const heartbeat_t& hb = logger.last();
  CHECK(hb.dropped == 0);
  CHECK(hb.errors == 0);
  CHECK(value_of(hb, "kernel_drops") == 0);
  CHECK(value_of(hb, "sequence_gaps") == 0);
  CHECK(value_of(hb, "rcvbuf_bytes") >= 1 << 20);
  CHECK(hb.status == "ok");
}

TEST_CASE("rotation (--rotate N --split-mb M): FILE.0 newest, at most N files, each within the size, the newest messages in order") {
  ScratchDir dir("rotate");
  LoggerUnderTest logger({"--rotate", "3", "--split-mb", "0.05", (dir / "log").string()});
  Publisher pub;
  for (uint32_t i = 0; i < 200; ++i) {
    auto data = payload(i, "R", 2000);
    REQUIRE(pub.raw("TEST_ROTATE", data));
    if (i % 20 == 19) usleep(20000);
  }
  REQUIRE(logger.wait_heartbeat([&](const heartbeat_t& hb) { return hb.received >= 200; }, 20s));
  CHECK(logger.stop().clean());
  for (int k = 0; k < 3; ++k) {
    INFO("file log." << k);
    REQUIRE(fs::exists(dir / ("log." + std::to_string(k))));
    CHECK(fs::file_size(dir / ("log." + std::to_string(k))) <= static_cast<uintmax_t>(0.05 * 1024 * 1024));
  }
  CHECK_FALSE(fs::exists(dir / "log.3"));
  // Oldest to newest: a contiguous run of indices ending with the last one published.
  std::vector<uint32_t> indices;
  for (const char* f : {"log.2", "log.1", "log.0"})
    for (const auto& l : only(read_log(dir / f), "TEST_ROTATE"))
      indices.push_back(l.data[0] | l.data[1] << 8 | l.data[2] << 16 | static_cast<uint32_t>(l.data[3]) << 24);
  REQUIRE(indices.size() >= 40);  // ~3 x 25 messages of 2 KB in 3 files of 50 KB (less the heartbeats')
  CHECK(indices.back() == 199);
  for (size_t k = 1; k < indices.size(); ++k) CHECK(indices[k] == indices[k - 1] + 1);
}

TEST_CASE("increment (--rotate 0 --split-mb M): FILE.00, FILE.01, ... together hold every message, in order") {
  ScratchDir dir("increment");
  LoggerUnderTest logger({"--rotate", "0", "--split-mb", "0.05", (dir / "log").string()});
  Publisher pub;
  for (uint32_t i = 0; i < 200; ++i) {
    auto data = payload(i, "S", 2000);
    REQUIRE(pub.raw("TEST_SPLIT", data));
  }
  REQUIRE(logger.wait_heartbeat([&](const heartbeat_t& hb) { return hb.received >= 200; }, 20s));
  CHECK(logger.stop().clean());
  std::vector<uint32_t> indices;
  int files = 0;
  for (int k = 0; fs::exists(dir / (k < 10 ? "log.0" + std::to_string(k) : "log." + std::to_string(k))); ++k, ++files) {
    const fs::path f = dir / (k < 10 ? "log.0" + std::to_string(k) : "log." + std::to_string(k));
    CHECK(fs::file_size(f) <= static_cast<uintmax_t>(0.05 * 1024 * 1024));
    for (const auto& l : only(read_log(f), "TEST_SPLIT")) indices.push_back(l.data[0] | l.data[1] << 8);
  }
  CHECK(files >= 8);  // 200 x 2 KB in 50 KB files
  REQUIRE(indices.size() == 200);
  for (uint32_t k = 0; k < 200; ++k) CHECK(indices[k] == k);
}

TEST_CASE("SIGTERM writes and flushes what was received, SIGHUP starts a new file") {
  ScratchDir dir("signals");
  // No periodic flush: whatever reaches the disk does so because of the stop.
  LoggerUnderTest logger({"--flush-ms", "600000", "--channels", "TEST_SIGNALS", (dir / "log").string()});
  Publisher pub;
  auto send = [&](uint32_t from, uint32_t to) {
    for (uint32_t i = from; i < to; ++i) {
      auto data = payload(i, "T", 60);
      REQUIRE(pub.raw("TEST_SIGNALS", data));
    }
  };
  send(0, 10);
  // Queued, not on the disk, and not counted as written: "published" is what reached the file.
  REQUIRE(logger.wait_heartbeat([](const heartbeat_t& hb) { return value_of(hb, "queue_bytes") >= 10 * 100; }, 10s));
  CHECK(logger.last().published == 0);
  CHECK(fs::file_size(dir / "log.00") == 0);
  ::kill(logger.proc().pid(), SIGHUP);
  REQUIRE(logger.wait_heartbeat([](const heartbeat_t& hb) { return value_of(hb, "files") == 2 && hb.published == 10; }, 10s));
  CHECK(fs::file_size(dir / "log.00") == 10 * 100);
  send(10, 30);
  REQUIRE(logger.wait_heartbeat([](const heartbeat_t& hb) { return value_of(hb, "queue_bytes") >= 20 * 100; }, 10s));
  // Not yet on the disk (no write for 10 minutes), and not counted.
  CHECK(fs::file_size(dir / "log.01") == 0);
  CHECK(logger.last().published == 10);
  const launcher::ExitStatus st = logger.stop();
  INFO(logger.stderr_text());
  CHECK(st.clean());
  auto indices = [&](const char* f) {
    std::vector<int> out;
    for (const auto& l : only(read_log(dir / f), "TEST_SIGNALS")) out.push_back(l.data[0]);
    return out;
  };
  std::vector<int> first(10), second(20);
  std::iota(first.begin(), first.end(), 0);
  std::iota(second.begin(), second.end(), 10);
  CHECK(indices("log.00") == first);
  CHECK(indices("log.01") == second);
  CHECK(logger.stderr_text().find("stopped: ") != std::string::npos);
}

TEST_CASE("exclusion: --exclude keeps the named channels out of the log, logs everything else, and counts what it left out") {
  ScratchDir dir("exclude");
  LoggerUnderTest logger({"--exclude", "BL_IMAGE|TEST_SECRET.*", (dir / "log").string()});
  Publisher pub;
  for (int i = 0; i < 20; ++i) {
    image_t img = frame(i, 20000);
    pub.typed(channel(kImageChannel), img);
    auto data = payload(i, "K", 100);
    pub.raw("TEST_KEEP", data);
    pub.raw("TEST_SECRET_A", data);
    pub.raw("BL_IMAGE_THUMB", data);  // a full match is needed: this one is kept
  }
  REQUIRE(logger.wait_heartbeat([](const heartbeat_t& hb) { return value_of(hb, "excluded") >= 40 && hb.received >= 40; }, 10s));
  CHECK(logger.stop().clean());
  const auto logged = read_log(dir / "log.00");
  CHECK(only(logged, "TEST_KEEP").size() == 20);
  CHECK(only(logged, "BL_IMAGE_THUMB").size() == 20);
  CHECK(only(logged, channel(kImageChannel)).empty());
  CHECK(only(logged, "TEST_SECRET_A").empty());
  CHECK(value_of(logger.last(), "excluded") == 40);
}

TEST_CASE("losses it can see are reported: a gap in a camera's frame numbers, and datagrams the kernel dropped") {
  ScratchDir dir("losses");
  Publisher pub;
  SECTION("frame-number gaps per source, a restarted source is not a loss") {
    LoggerUnderTest logger({(dir / "log").string()});
    for (int64_t n : {0, 1, 2, 5, 6, 0, 1}) {
      image_t img = frame(n, 1000);
      pub.typed(channel(kImageChannel), img);
    }
    image_t other = frame(100, 1000, "another-camera");
    pub.typed(channel(kImageChannel), other);
    // The restart comes after the gap, and each heartbeat carries the whole state.
    REQUIRE(logger.wait_heartbeat([](const heartbeat_t& hb) { return value_of(hb, "source_restarts") >= 1; }, 10s));
    const heartbeat_t& hb = logger.last();
    CHECK(value_of(hb, "sequence_gaps") == 2);
    CHECK(value_of(hb, "source_restarts") == 1);
    CHECK(hb.status.rfind("LOSING", 0) == 0);
    CHECK(logger.stop().clean());
  }
  SECTION("a stopped logger with a small receive buffer: the kernel's drops on its socket are counted") {
    LoggerUnderTest logger({"--recv-buf-mb", "0.25", (dir / "log").string()});
    CHECK(value_of(logger.last(), "kernel_drops") == 0);
    logger.proc().signal(SIGSTOP);
    for (uint32_t i = 0; i < 200; ++i) {  // 12 MB into a 0.5 MB buffer nobody reads
      auto data = payload(i, "F", 60000);
      pub.raw("TEST_FLOOD", data);
    }
    logger.proc().signal(SIGCONT);
    REQUIRE(logger.wait_heartbeat([](const heartbeat_t& hb) { return value_of(hb, "kernel_drops") > 0; }, 10s));
    CHECK(logger.last().status.rfind("LOSING", 0) == 0);
    CHECK(logger.stop().clean());
  }
}

TEST_CASE("bad arguments are clear errors (exit 2), an unwritable log is an error at start (exit 1)") {
  std::string err;
  CHECK(run_logger_expecting_exit({}, err) == 2);
  CHECK(err.find("expected 1 argument(s), got 0") != std::string::npos);
  CHECK(run_logger_expecting_exit({"--rotate", "-1", "x"}, err) == 2);
  CHECK(err.find("--rotate must be in [0, 100000], got -1") != std::string::npos);
  CHECK(run_logger_expecting_exit({"--split-mb", "ten", "x"}, err) == 2);
  CHECK(err.find("--split-mb expects a finite number, got 'ten'") != std::string::npos);
  CHECK(run_logger_expecting_exit({"--exclude", "BL_(IMAGE", "x"}, err) == 2);
  CHECK(err.find("--exclude 'BL_(IMAGE' is not a valid regular expression") != std::string::npos);
  CHECK(run_logger_expecting_exit({"--queue-capacity", "0", "x"}, err) == 2);
  CHECK(err.find("--queue-capacity must be in [1, 100000000], got 0") != std::string::npos);
  CHECK(run_logger_expecting_exit({"--rotat", "3", "x"}, err) == 2);
  CHECK(err.find("unknown flag --rotat") != std::string::npos);
  CHECK(run_logger_expecting_exit({"--lcm-url", "udpm://239.255.76.67:7667?ttl=5", "x"}, err) == 2);
  CHECK(err.find("ttl") != std::string::npos);
  CHECK(run_logger_expecting_exit({"/proc/version/log"}, err) == 1);
  CHECK(err.find("cannot create the log directory /proc/version") != std::string::npos);
}
