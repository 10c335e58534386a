// bricklayer-logger's node: records the bus into standard LCM log files (lcm-logplayer, lcm::LogFile and
// bricklayer-replay read them), without losing messages under load, and says so when it does.
//
// Why not Debian's lcm-logger 1.3.1: its subscription keeps LCM's default queue of 30 messages and
// silently discards new ones when full; at 60 camera frames a second a 0.1 s stall of its handler
// thread loses a message (the 10-minute soak lost 1 prediction in 27,709). Here LCM's queue is large,
// the handler only copies into a queue bounded in bytes, a writer thread does the disk
// (event_writer.h), and every loss the logger can see is counted: its own queue overflowing, the
// kernel dropping datagrams on its socket (udp_socket_stats.h), and gaps in the numbers our messages
// carry (sequence_gaps.h).
//
// Subscribes: every channel (".*"; --channels / --exclude narrow it).
// Publishes: BL_HEARTBEAT (module "logger"): received = messages taken, published = events written,
//   dropped = events its full queue refused, errors = events the file refused; values: kernel_drops,
//   sequence_gaps, source_restarts, excluded, bytes_written, queue_bytes, queue_peak_bytes, files,
//   rcvbuf_bytes. Status "ok" only while nothing is known lost.
// Files: FILE.0 with --rotate N (older parts FILE.1 ... FILE.<N-1>), else FILE.00, FILE.01, ... and the
//   recording's index FILE.index (recording_index.h); --split-mb starts a new file, and so does SIGHUP.
//   --budget-mb / --min-free-mb keep the series (--series PREFIX) within its disk budget by deleting the
//   oldest recordings first (disk_budget.h). --frame-rate thins camera frames outside the full-rate
//   windows around moments (recording_policy.h, moment_detector.h). SIGINT/SIGTERM: what was received is
//   written and synced, then exit 0.
// Values also: lost (received, not kept: no room), deleted_files, deleted_bytes, series_bytes,
//   free_bytes, budget_bytes, frames_kept, frames_thinned, answers_thinned, window_frames_refused,
//   held_bytes, moments.
#pragma once

#include <atomic>
#include <cstdint>
#include <memory>
#include <regex>
#include <string>
#include <unordered_map>

#include "bricklayer/logger/event_writer.h"
#include "bricklayer/logger/moment_detector.h"
#include "bricklayer/logger/recording_policy.h"
#include "bricklayer/logger/sequence_gaps.h"
#include "bricklayer/runtime/config.h"
#include "bricklayer/runtime/lcm_bus.h"
#include "bricklayer/runtime/node.h"

namespace bricklayer::logger {

struct LoggerConfig {
  std::string file;
  int rotate = 0;
  double split_mb = 0;
  bool strftime = false;
  std::string channels = ".*";
  std::string exclude;
  int flush_ms = 100;
  double max_unwritten_mb = 256;
  int queue_capacity = 1000000;
  double recv_buf_mb = 16;
  double budget_mb = 0;
  double min_free_mb = 0;
  std::string series;
  double frame_rate = 0;
  double full_rate_before_s = 10;
  double full_rate_after_s = 10;
  bool answers_with_frames = false;
  double max_mb_per_hour = 0;
  bool no_index = false;

  template <typename Visitor>
  void visit(Visitor& v) {
    v(runtime::param("FILE", file, "log file name without suffix (strftime conversions with --strftime)")
          .argument()
          .must([](const std::string& f) { return f.empty() ? std::string("is empty") : std::string(); }));
    v(runtime::param("rotate", rotate, "keep FILE.0 .. FILE.<N-1>, newest FILE.0; 0 = increment FILE.00, FILE.01, ...")
          .range(0, 100000));
    v(runtime::param("split-mb", split_mb, "start a new file before one would exceed this many MB (0 = never)").at_least(0));
    v(runtime::param("strftime", strftime, "expand strftime conversions (%Y%m%d-%H%M%S) in FILE with the local time at start"));
    v(runtime::param("channels", channels, "log only channels fully matching this regular expression").must(regex_rule));
    v(runtime::param("exclude", exclude, "do not log channels fully matching this regular expression (e.g. BL_IMAGE)")
          .must(regex_rule));
    v(runtime::param("flush-ms", flush_ms, "flush the file this often; 0 = after every batch of events").range(0, 600000));
    v(runtime::param("max-unwritten-mb", max_unwritten_mb, "received-but-unwritten bound; beyond it events are dropped and counted")
          .above(0));
    v(runtime::param("queue-capacity", queue_capacity, "messages LCM may hold for the logger before it discards (LCM's default: 30)")
          .range(1, 100000000));
    v(runtime::param("recv-buf-mb", recv_buf_mb, "kernel receive buffer to ask for (capped at net.core.rmem_max unless root)")
          .range(0, 1024));
    v(runtime::param("budget-mb", budget_mb, "the series may use at most this many MB of disk; the oldest recordings are deleted first (0 = no limit)")
          .at_least(0));
    v(runtime::param("min-free-mb", min_free_mb, "leave at least this many MB free on the disk, deleting the oldest recordings first (0 = none)")
          .at_least(0));
    v(runtime::param("series", series, "the budget covers every recording in FILE's folder whose name starts with this (default: this recording only)")
          .must([](const std::string& s) { return s.find('/') != std::string::npos ? std::string("is a file name prefix, not a path") : std::string(); }));
    v(runtime::param("frame-rate", frame_rate, "camera frames kept per second outside full-rate windows (0 = every frame)").range(0, 1000));
    v(runtime::param("full-rate-before-s", full_rate_before_s, "with --frame-rate: every frame this long before a moment (red, collapse, round end, mark)")
          .range(0, 600));
    v(runtime::param("full-rate-after-s", full_rate_after_s, "with --frame-rate: every frame this long after a moment").range(0, 600));
    v(runtime::param("answers-with-frames", answers_with_frames,
                     "with --frame-rate: a thinned frame's stacks, predictions, timings and previews are thinned with it"));
    v(runtime::param("max-mb-per-hour", max_mb_per_hour,
                     "with --frame-rate: windows keep full rate only while the recording stays within this many MB "
                     "(1e6 bytes) an hour on average, one hour's worth at most at once; an operator's mark always "
                     "(0 = no limit)")
          .range(0, 1e6));
    v(runtime::param("no-index", no_index, "write no FILE.index (it is never written with --rotate > 0: rotation renames the parts)"));
  }
  // "" for a valid regular expression, else why not.
  static std::string regex_rule(const std::string& pattern);
};

// The channels whose messages answer one camera frame (stacks, predictions, timings, previews, simcam's
// truth): with --answers-with-frames they are thinned with the frame they answer.
std::vector<std::string> answer_channels();

class LoggerNode final : public runtime::Node {
 public:
  using Config = LoggerConfig;
  static constexpr const char* kProgram = "bricklayer-logger";
  static constexpr const char* kSummary =
      "Records every message on the bus into standard LCM log files, counting every loss it can see.\n"
      "File naming and rotation as lcm-logger: --rotate N writes FILE.0 (older parts FILE.1 ...\n"
      "FILE.<N-1>); --rotate 0 writes FILE.00, FILE.01, ... SIGHUP starts a new file; SIGINT/SIGTERM\n"
      "write, flush and sync what was received, then exit 0.";

  // Opens the first file; throws std::runtime_error naming it when it cannot.
  LoggerNode(const Config& config, runtime::Bus& bus);
  ~LoggerNode() override;

  // LCM may hold --queue-capacity messages for the logger; SIGHUP is blocked before any thread starts.
  static runtime::LcmBusOptions bus_options(const Config& config);

  // The next event goes into a new file (what SIGHUP does).
  void request_new_file() { writer_->request_new_file(); }
  WriterStats writer_stats() const { return writer_->stats(); }
  const RecordingPolicy& policy() const { return policy_; }

  // Rules across fields (node_main calls it; the constructor too).
  static void check(const Config& config);

 protected:
  void tick() override;
  void before_heartbeat() override { update_figures(); }
  void before_stop() override;

 private:
  void on_message(const runtime::Received& r);
  bool wanted(const std::string& channel);
  void observe_sequence(const Event& e);  // a frame as it arrives (the bus thread)
  void update_figures();

  std::regex channels_;
  bool has_exclude_;
  std::regex exclude_;
  std::unordered_map<std::string, bool> wanted_;
  const std::string image_channel_;
  const int port_;
  int64_t excluded_ = 0;
  int64_t kernel_drops_ = 0;
  int64_t rcvbuf_bytes_ = 0;
  int64_t next_socket_check_utime_ = 0;
  MomentDetector moments_;
  RecordingPolicy policy_;
  int64_t moments_seen_ = 0;
  int64_t budget_bytes_ = 0;
  SequenceGaps sequence_;  // the bus thread only
  std::atomic<int64_t> gaps_{0}, source_restarts_{0};
  std::unique_ptr<EventWriter> writer_;  // last: its thread uses the members above, and stops first
};

}  // namespace bricklayer::logger
