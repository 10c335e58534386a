// The logger's pieces without the bus: file naming and rotation (lcm-logger's rules), the writer
// thread (every event written byte-identical and in order, split by size, the byte bound on its
// queue), and frame-number gaps.
#include <catch2/catch.hpp>

#include <lcm/lcm-cpp.hpp>
#include <unistd.h>

#include <atomic>
#include <filesystem>
#include <mutex>
#include <fstream>
#include <map>
#include <memory>

#include "bricklayer/logger/event_writer.h"
#include "bricklayer/logger/log_series.h"
#include "bricklayer/logger/sequence_gaps.h"

using namespace bricklayer::logger;
namespace fs = std::filesystem;

namespace {

struct TempDir {
  fs::path path;
  explicit TempDir(const std::string& tag) {
    path = fs::temp_directory_path() / ("bricklayer-logger-" + tag + "-" + std::to_string(::getpid()));
    fs::remove_all(path);
    fs::create_directories(path);
  }
  ~TempDir() {
    std::error_code ec;
    fs::remove_all(path, ec);
  }
};

void touch(const fs::path& p, const std::string& text) { std::ofstream(p) << text; }
std::string slurp(const fs::path& p) {
  std::ifstream in(p);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

// Every event of an LCM log file, in file order.
std::vector<Event> read_log(const fs::path& p) {
  std::vector<Event> out;
  auto log = std::make_unique<lcm::LogFile>(p.string(), "r");
  REQUIRE(log->good());
  while (const lcm::LogEvent* e = log->readNextEvent()) {
    Event ev;
    ev.utime = e->timestamp;
    ev.channel = e->channel;
    const auto* b = static_cast<const uint8_t*>(e->data);
    ev.data.assign(b, b + e->datalen);
    out.push_back(std::move(ev));
  }
  return out;
}

// A deterministic payload: n bytes that depend on (i, channel).
Event make_event(int i, const std::string& ch, size_t n) {
  Event e;
  e.utime = 1000000 + i;
  e.channel = ch;
  e.data.resize(n);
  for (size_t k = 0; k < n; ++k) e.data[k] = static_cast<uint8_t>((i * 131 + k * 7 + ch.size()) & 0xff);
  return e;
}

}  // namespace

TEST_CASE("rotate N: always FILE.0, older parts shift to FILE.1 .. FILE.<N-1>, the oldest is deleted") {
  TempDir dir("rotate");
  const std::string base = (dir.path / "sub" / "log").string();
  LogSeries series(base, 3);
  for (int round = 0; round < 5; ++round) {
    const std::string path = series.next();
    CHECK(path == base + ".0");
    CHECK_FALSE(fs::exists(path));  // moved out of the way
    touch(path, "round" + std::to_string(round));
  }
  CHECK(slurp(base + ".0") == "round4");
  CHECK(slurp(base + ".1") == "round3");
  CHECK(slurp(base + ".2") == "round2");
  CHECK_FALSE(fs::exists(base + ".3"));
}

TEST_CASE("rotate 0: FILE.00, FILE.01, ... after the highest number, never reused, nothing is renamed or deleted") {
  TempDir dir("increment");
  const std::string base = (dir.path / "log").string();
  touch(base + ".00", "someone else's");
  LogSeries series(base, 0);
  const std::string first = series.next();
  CHECK(first == base + ".01");
  touch(first, "x");
  CHECK(series.next() == base + ".02");
  CHECK(slurp(base + ".00") == "someone else's");
  fs::remove(first);  // deleted by the disk budget: its number is not used again
  CHECK(series.next() == base + ".03");
  touch(base + ".07", "a restarted logger's");
  CHECK(LogSeries(base, 0).next() == base + ".08");
}

TEST_CASE("bad series arguments and strftime patterns are clear errors") {
  CHECK_THROWS_WITH(LogSeries("", 0), Catch::Contains("empty"));
  CHECK_THROWS_WITH(LogSeries("x", -1), Catch::Contains("rotate must be >= 0"));
  CHECK(expand_strftime("logs/run-%Y", 0).substr(0, 11) == "logs/run-19");  // 1970 (or 1969 west of UTC)
  CHECK_THROWS_WITH(expand_strftime("", 0), Catch::Contains("expands to nothing"));
  LogSeries blocked("/proc/version/sub/log", 1);  // a path under a file
  CHECK_THROWS_WITH(blocked.next(), Catch::Contains("cannot create the log directory"));
}

TEST_CASE("the writer writes every event byte-identical, in order, splitting before a file would exceed the size") {
  TempDir dir("writer");
  WriterOptions o;
  o.base = (dir.path / "log").string();
  o.rotate = 0;
  o.split_bytes = 20000;
  o.flush_ms = 10;
  std::vector<Event> sent;
  int written_callbacks = 0;
  {
    EventWriter w(o, [&](const Event&) { ++written_callbacks; });
    for (int i = 0; i < 300; ++i) {
      Event e = make_event(i, i % 3 == 0 ? "BL_IMAGE" : "BL_STACK", i % 3 == 0 ? 3000 : 100 + i);
      sent.push_back(e);
      REQUIRE(w.push(std::move(e)));
    }
    w.stop();
    const WriterStats s = w.stats();
    CHECK(s.written == 300);
    CHECK(s.dropped == 0);
    CHECK(s.write_errors == 0);
    CHECK(s.queued_bytes == 0);
    CHECK(s.files >= 2);
  }
  CHECK(written_callbacks == 300);
  std::vector<fs::path> files;
  for (const auto& e : fs::directory_iterator(dir.path)) files.push_back(e.path());
  std::sort(files.begin(), files.end());
  REQUIRE(files.size() >= 2);
  std::vector<Event> logged;
  for (const auto& f : files) {
    CHECK(static_cast<int64_t>(fs::file_size(f)) <= o.split_bytes);
    for (auto& e : read_log(f)) logged.push_back(std::move(e));
  }
  REQUIRE(logged.size() == sent.size());
  for (size_t i = 0; i < sent.size(); ++i) {
    INFO("event " << i);
    CHECK(logged[i].channel == sent[i].channel);
    CHECK(logged[i].utime == sent[i].utime);
    CHECK(logged[i].data == sent[i].data);
  }
}

TEST_CASE("the writer's queue is bounded in bytes: beyond it events are refused and counted, never lost silently") {
  TempDir dir("bound");
  WriterOptions o;
  o.base = (dir.path / "log").string();
  o.max_unwritten_bytes = 10000;
  // Hold the writer thread inside its callback so the queue can only fill. An event counts against
  // the bound until it is written, so the held one (100 bytes in a file) still does.
  std::mutex gate;
  std::unique_lock hold(gate);
  std::atomic<bool> writer_busy{false};
  EventWriter w(o, [&](const Event&) {
    writer_busy = true;
    std::lock_guard wait_for_test(gate);
  });
  REQUIRE(w.push(make_event(0, "A", 71)));
  for (int i = 0; i < 400 && !writer_busy; ++i) usleep(5000);
  REQUIRE(writer_busy);
  int accepted = 0, refused = 0;
  for (int i = 1; i <= 50; ++i) {
    if (w.push(make_event(i, "A", 971)))  // 1000 bytes each in a file
      ++accepted;
    else
      ++refused;
  }
  CHECK(accepted == 9);
  CHECK(refused == 41);
  CHECK(w.stats().dropped == 41);
  CHECK(w.stats().peak_queued_bytes == 9100);
  hold.unlock();
  w.stop();
  CHECK(w.stats().written == 10);
  CHECK(read_log(dir.path / "log.00").size() == 10);
}

TEST_CASE("frame-number gaps count lost frames per source, a step back is a restart, not a loss") {
  SequenceGaps g;
  CHECK(g.observe("BL_IMAGE", "cam", 10) == 0);
  CHECK(g.observe("BL_IMAGE", "cam", 11) == 0);
  CHECK(g.observe("BL_IMAGE", "other", 500) == 0);  // its own stream
  CHECK(g.observe("BL_IMAGE", "cam", 14) == 2);
  CHECK(g.observe("BL_IMAGE", "cam", 0) == 0);  // source restarted
  CHECK(g.observe("BL_IMAGE", "cam", 1) == 0);
  CHECK(g.observe("BL_IMAGE", "other", 501) == 0);
  CHECK(g.observe("BL_IMAGE", "cam", 4000000000000) == 0);  // a new numbering, not four trillion losses
  CHECK(g.missing() == 2);
  CHECK(g.restarts() == 2);
  for (int i = 0; i < 1000; ++i) g.observe("BL_IMAGE", "hostile" + std::to_string(i), 0);
  CHECK(g.streams() <= SequenceGaps::kMaxStreams);
}
