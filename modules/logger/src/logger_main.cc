// bricklayer-logger: records the bus into standard LCM log files (lcm-logplayer, lcm::LogFile and
// bricklayer-replay read them), without losing messages under load, and says so when it does.
//
// Why not Debian's lcm-logger 1.3.1: its subscription keeps LCM's default queue of 30 messages and
// silently discards new ones when full; at 60 camera frames a second a 0.1 s stall of its handler
// thread loses a message (the 10-minute soak lost 1 prediction in 27,709). Here the subscription
// queue is large, the handler only copies into a queue bounded in bytes, a writer thread does the
// disk (event_writer.h), and every loss the logger can see is counted: its own queue overflowing,
// the kernel dropping datagrams on its socket (udp_socket_stats.h), and gaps in the numbers our
// messages carry (sequence_gaps.h).
//
// Subscribes: every channel (".*"; --channels / --exclude narrow it).
// Publishes: BL_HEARTBEAT (module "logger"): received = messages taken, published = events written,
//   dropped = events its full queue refused, errors = events the file refused; values: kernel_drops,
//   sequence_gaps, source_restarts, excluded, bytes_written, queue_bytes, queue_peak_bytes, files,
//   rcvbuf_bytes. Status "ok" only while nothing is known lost.
// Files: FILE.0 with --rotate N (older parts FILE.1 ... FILE.<N-1>), else FILE.00, FILE.01, ...;
//   --split-mb starts a new file, and so does SIGHUP. SIGINT/SIGTERM: what was received is written,
//   flushed and synced, then exit 0.
#include <lcm/lcm-cpp.hpp>
#include <pthread.h>
#include <signal.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <ctime>
#include <regex>
#include <string>
#include <unordered_map>

#include "bricklayer/common/channels.h"
#include "bricklayer/common/flags.h"
#include "bricklayer/common/lcm_url.h"
#include "bricklayer/common/log.h"
#include "bricklayer/common/module.h"
#include "bricklayer/image_t.hpp"
#include "bricklayer/logger/event_writer.h"
#include "bricklayer/logger/log_series.h"
#include "bricklayer/logger/sequence_gaps.h"
#include "bricklayer/logger/udp_socket_stats.h"

namespace bricklayer::logger {
namespace {

// SIGHUP (start a new file) is blocked in every thread and collected in Tick(): a handler would
// interrupt LCM's poll, which the run loop counts as a receive failure.
void block_sighup() {
  sigset_t set;
  sigemptyset(&set);
  sigaddset(&set, SIGHUP);
  pthread_sigmask(SIG_BLOCK, &set, nullptr);
}
bool take_sighup() {
  sigset_t set;
  sigemptyset(&set);
  sigaddset(&set, SIGHUP);
  const timespec zero{0, 0};
  return sigtimedwait(&set, nullptr, &zero) == SIGHUP;
}

std::regex compile(const std::string& flag, const std::string& pattern) {
  try {
    return std::regex(pattern);
  } catch (const std::regex_error& e) {
    throw FlagError("--" + flag + " '" + pattern + "' is not a valid regular expression: " + e.what());
  }
}

struct LoggerConfig {
  std::string url;
  WriterOptions writer;
  std::string channels = ".*";
  std::string exclude;
  int queue_capacity = 1000000;
  int64_t recv_buf_bytes = 16 << 20;
};

class Logger {
 public:
  explicit Logger(const LoggerConfig& c)
      : module_("logger", c.url),
        channels_(compile("channels", c.channels)),
        has_exclude_(!c.exclude.empty()),
        exclude_(compile("exclude", c.exclude.empty() ? "^$" : c.exclude)),
        image_channel_(channel(kImageChannel)),
        port_(udpm_port(c.url)),
        writer_(c.writer, [this](const Event& e) { OnWritten(e); }) {
    // LCM matches the subscription regex against the whole channel name; --channels narrows in
    // Wanted() (the same full match), so one subscription sees everything and counts what it skips.
    lcm::Subscription* s = module_.lcm().subscribeFunction(".*", &Logger::OnMessage, this);
    if (!s) throw std::runtime_error("cannot subscribe to the bus");
    s->setQueueCapacity(c.queue_capacity);
    if (port_ > 0) {
      UdpSocketStats st = raise_receive_buffer(port_, c.recv_buf_bytes);
      rcvbuf_bytes_ = st.rcvbuf_bytes;
      if (st.sockets == 0)
        log::warn("found no socket of this process on UDP port ", port_, ": kernel drops cannot be counted");
      else if (st.rcvbuf_bytes < c.recv_buf_bytes)
        log::warn("the kernel gave a ", st.rcvbuf_bytes, "-byte receive buffer of the ", c.recv_buf_bytes,
                  " asked (capped by net.core.rmem_max; run as root or: sysctl -w net.core.rmem_max=",
                  c.recv_buf_bytes, ")");
    }
    log::info("logging ", c.url, " into ", writer_.stats().current_file, " (receive buffer ", rcvbuf_bytes_,
              " bytes, queue ", c.queue_capacity, " messages / ", c.writer.max_unwritten_bytes >> 20, " MB)");
  }

  int Run() {
    Tick();
    const int rc = module_.run([this] { Tick(); }, 20);
    // Stopping: take what LCM still holds (until the bus is quiet for 50 ms, at most 1 s), then write,
    // flush and sync it all.
    const auto until = std::chrono::steady_clock::now() + std::chrono::seconds(1);
    while (std::chrono::steady_clock::now() < until && module_.lcm().handleTimeout(50) > 0) {
    }
    writer_.stop();
    Tick();
    const WriterStats w = writer_.stats();
    log::info("stopped: ", module_.counters().received.load(), " received, ", w.written, " written (", w.bytes,
              " bytes, ", w.files, " file(s), last ", w.current_file, "), ", w.dropped, " dropped (queue full), ",
              kernel_drops_, " kernel drops, ", gaps_.load(), " sequence gaps, ", w.write_errors, " write errors, ",
              excluded_, " excluded");
    module_.publish_heartbeat();  // the final figures, for the launcher's summary
    return rc;
  }

 private:
  static void OnMessage(const lcm::ReceiveBuffer* rbuf, const std::string& ch, Logger* self) {
    // Only a copy here: this thread must get back to LCM's queue quickly. Nothing may throw into LCM.
    try {
      if (!self->Wanted(ch)) {
        ++self->excluded_;
        return;
      }
      Event e;
      e.utime = rbuf->recv_utime;
      e.channel = ch;
      const auto* bytes = static_cast<const uint8_t*>(rbuf->data);
      e.data.assign(bytes, bytes + rbuf->data_size);
      ++self->module_.counters().received;
      self->writer_.push(std::move(e));
    } catch (const std::exception& ex) {
      ++self->module_.counters().errors;
      log::error("could not queue a message on ", ch, ": ", ex.what());
    }
  }

  bool Wanted(const std::string& ch) {
    if (auto it = wanted_.find(ch); it != wanted_.end()) return it->second;
    const bool wanted = std::regex_match(ch, channels_) && !(has_exclude_ && std::regex_match(ch, exclude_));
    if (wanted_.size() < 4096) wanted_.emplace(ch, wanted);  // bounded: channel names come from the network
    return wanted;
  }

  // Writer thread: numbers that skip reveal messages lost before they reached us.
  void OnWritten(const Event& e) {
    if (e.channel != image_channel_) return;
    image_t img{};
    if (img.decode(e.data.data(), 0, static_cast<int>(e.data.size())) < 0) return;  // logged as bytes anyway
    if (const int64_t skipped = sequence_.observe(e.channel, img.source, img.frame_number); skipped > 0)
      log::warn(e.channel, " from ", img.source, ": ", skipped, " frame(s) before ", img.frame_number,
                " never reached the logger");
    gaps_ = sequence_.missing();
    source_restarts_ = sequence_.restarts();
  }

  void Tick() {
    const WriterStats w = writer_.stats();
    Counters& c = module_.counters();
    c.published = w.written;
    c.dropped = w.dropped;
    c.errors = w.write_errors;
    const auto now = std::chrono::steady_clock::now();
    if (port_ > 0 && now >= next_socket_check_) {
      const UdpSocketStats st = udp_socket_stats(port_);
      kernel_drops_ = st.drops;
      rcvbuf_bytes_ = st.rcvbuf_bytes;
      next_socket_check_ = now + std::chrono::milliseconds(500);
    }
    module_.set_value("kernel_drops", static_cast<double>(kernel_drops_));
    module_.set_value("sequence_gaps", static_cast<double>(gaps_.load()));
    module_.set_value("source_restarts", static_cast<double>(source_restarts_.load()));
    module_.set_value("excluded", static_cast<double>(excluded_));
    module_.set_value("bytes_written", static_cast<double>(w.bytes));
    module_.set_value("queue_bytes", static_cast<double>(w.queued_bytes));
    module_.set_value("queue_peak_bytes", static_cast<double>(w.peak_queued_bytes));
    module_.set_value("files", static_cast<double>(w.files));
    module_.set_value("rcvbuf_bytes", static_cast<double>(rcvbuf_bytes_));
    const int64_t lost = w.dropped + kernel_drops_ + gaps_.load();
    if (lost > 0 || w.write_errors > 0) {
      module_.set_status("LOSING: " + std::to_string(w.dropped) + " queue-full drops, " + std::to_string(kernel_drops_) +
                         " kernel drops, " + std::to_string(gaps_.load()) + " sequence gaps, " +
                         std::to_string(w.write_errors) + " write errors");
    } else {
      module_.set_status("ok");
    }
    if (take_sighup()) writer_.request_new_file();
  }

  Module module_;  // first: owns the LCM handle the subscription lives on
  std::regex channels_;
  bool has_exclude_;
  std::regex exclude_;
  std::unordered_map<std::string, bool> wanted_;
  const std::string image_channel_;
  const int port_;
  int64_t excluded_ = 0;
  int64_t kernel_drops_ = 0;
  int64_t rcvbuf_bytes_ = 0;
  std::chrono::steady_clock::time_point next_socket_check_{};
  SequenceGaps sequence_;  // writer thread only
  std::atomic<int64_t> gaps_{0}, source_restarts_{0};
  EventWriter writer_;  // last: its thread uses the members above, and stops first
};

int Main(int argc, char** argv) {
  Flags f("bricklayer-logger",
          "Records every message on the bus into standard LCM log files, counting every loss it can see.\n"
          "File naming and rotation as lcm-logger: --rotate N writes FILE.0 (older parts FILE.1 ...\n"
          "FILE.<N-1>); --rotate 0 writes FILE.00, FILE.01, ... SIGHUP starts a new file; SIGINT/SIGTERM\n"
          "write, flush and sync what was received, then exit 0.");
  f.add_positional("FILE", "log file name without suffix (strftime conversions with --strftime)");
  f.add("lcm-url", "", "LCM URL (default: $LCM_DEFAULT_URL, else host-only udpm ttl=0)");
  f.add("rotate", "0", "keep FILE.0 .. FILE.<N-1>, newest FILE.0; 0 = increment FILE.00, FILE.01, ...");
  f.add("split-mb", "0", "start a new file before one would exceed this many MB (0 = never)");
  f.add_bool("strftime", "expand strftime conversions (%Y%m%d-%H%M%S) in FILE with the local time at start");
  f.add("channels", ".*", "log only channels fully matching this regular expression");
  f.add("exclude", "", "do not log channels fully matching this regular expression (e.g. BL_IMAGE)");
  f.add("flush-ms", "100", "flush the file this often; 0 = after every batch of events");
  f.add("max-unwritten-mb", "256", "received-but-unwritten bound; beyond it events are dropped and counted");
  f.add("queue-capacity", "1000000", "messages LCM may hold for the logger before it discards (LCM's default: 30)");
  f.add("recv-buf-mb", "16", "kernel receive buffer to ask for (capped at net.core.rmem_max unless root)");
  f.add("log-level", "info", "debug, info, warn or error");
  if (!f.parse(argc, argv)) return 0;
  log::set_level(log::parse_level(f.get("log-level")));

  LoggerConfig c;
  c.url = resolve_lcm_url(f.get("lcm-url"));
  try {
    check_lcm_url(c.url);
  } catch (const std::invalid_argument& e) {
    throw FlagError(e.what());  // a bad URL is a bad argument: exit 2
  }
  const int64_t rotate = f.get_int("rotate");
  if (rotate < 0 || rotate > 100000) throw FlagError("--rotate must be between 0 and 100000, got " + std::to_string(rotate));
  const double split_mb = f.get_double("split-mb");
  if (split_mb < 0) throw FlagError("--split-mb must be >= 0 (0 = never split), got " + f.get("split-mb"));
  const int64_t flush_ms = f.get_int("flush-ms");
  if (flush_ms < 0 || flush_ms > 600000) throw FlagError("--flush-ms must be between 0 and 600000, got " + f.get("flush-ms"));
  const double unwritten_mb = f.get_double("max-unwritten-mb");
  if (unwritten_mb <= 0) throw FlagError("--max-unwritten-mb must be > 0, got " + f.get("max-unwritten-mb"));
  const int64_t capacity = f.get_int("queue-capacity");
  if (capacity < 1 || capacity > 100000000)
    throw FlagError("--queue-capacity must be between 1 and 100000000, got " + f.get("queue-capacity"));
  const double recv_mb = f.get_double("recv-buf-mb");
  if (recv_mb < 0 || recv_mb > 1024) throw FlagError("--recv-buf-mb must be between 0 and 1024, got " + f.get("recv-buf-mb"));
  std::string file = f.positional().at(0);
  if (file.empty()) throw FlagError("FILE is empty");
  if (f.get_bool("strftime")) file = expand_strftime(file, static_cast<long long>(std::time(nullptr)));

  c.writer.base = file;
  c.writer.rotate = static_cast<int>(rotate);
  c.writer.split_bytes = static_cast<int64_t>(std::llround(split_mb * 1024 * 1024));
  c.writer.flush_ms = static_cast<int>(flush_ms);
  c.writer.max_unwritten_bytes = static_cast<int64_t>(std::llround(unwritten_mb * 1024 * 1024));
  c.channels = f.get("channels");
  c.exclude = f.get("exclude");
  compile("channels", c.channels);  // bad patterns are flag errors (exit 2) before anything opens
  if (!c.exclude.empty()) compile("exclude", c.exclude);
  c.queue_capacity = static_cast<int>(capacity);
  c.recv_buf_bytes = static_cast<int64_t>(std::llround(recv_mb * 1024 * 1024));
  block_sighup();  // before LCM and the writer start their threads, which inherit the mask
  Logger logger(c);
  return logger.Run();
}

}  // namespace
}  // namespace bricklayer::logger

int main(int argc, char** argv) {
  return bricklayer::run_main("bricklayer-logger", &bricklayer::logger::Main, argc, argv);
}
