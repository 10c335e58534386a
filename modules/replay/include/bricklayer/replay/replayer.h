// Runs modules' real nodes on a recorded log (openpilot's process_replay and Drake's LcmDrivenLoop in
// spirit): the recorded events are delivered in order on an in-process bus whose clock is each event's
// recorded utime (between events it moves in 20 ms steps, as a live node's loop ticks, so timers fire
// at the same moments in every replay); after each event every node handles what it was given and what
// the others published, so chained modules (vision -> prediction) feed each other. The recorded
// events on the replayed modules' output channels are not delivered: they are what the replay is
// compared with. Each node is built from the configuration it recorded on BL_CONFIG.
#pragma once

#include <cstdint>
#include <deque>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "bricklayer/common/channels.h"
#include "bricklayer/frames/decode_ahead.h"
#include "bricklayer/replay/message_diff.h"
#include "bricklayer/replay/module_adapter.h"
#include "bricklayer/replay/recording.h"
#include "bricklayer/runtime/in_process_bus.h"

namespace bricklayer::replay {

struct ReplayOptions {
  std::vector<std::string> modules;  // in chain order, e.g. {"vision", "prediction"}
  std::vector<std::string> sets;     // "name=value" (every module that has the field; else an error) or "module.name=value"
  int64_t from_utime = 0;            // events before are skipped (their configuration still read)
  int64_t to_utime = INT64_MAX;      // the replay ends after the last event at or before this
};

struct ReplayedModule {
  std::string name;
  std::string config_json;        // what it ran with
  bool config_recorded = false;   // from the log's BL_CONFIG (else its defaults)
  int64_t start_utime = 0;        // when its node starts: as the recorded one did (its first heartbeat's
                                  // time less its uptime), or the range's start if it was already up
  std::vector<std::string> notes;
};

// What a log says about a module near the start of a range.
struct RecordedModule {
  std::string module;
  std::string config_json;   // its first node_config_t in the range ("" = none seen)
  int64_t start_utime = -1;  // when its process started (first heartbeat's utime - uptime_us), -1 = unknown
};

class Replayer {
 public:
  // Something the replay saw: a recorded event (recorded = true) on a compared channel, or an output
  // a replayed node published (recorded = false), with the log time.
  using Sink = std::function<void(bool recorded, const std::string& channel, const std::vector<uint8_t>& bytes,
                                  int64_t utime)>;
  // sources: as RecordingReader. Throws std::invalid_argument for a bad module or --set, and
  // std::runtime_error when the log cannot be read.
  Replayer(std::vector<std::string> sources, ReplayOptions options, Sink sink);
  ~Replayer();

  // Sees every event read in the range (every channel), before it is delivered.
  void set_observer(std::function<void(const runtime::LogEvent&)> observer) { observer_ = std::move(observer); }

  // Replays to the end of the range. progress(done_bytes, total_bytes, log_utime) is called now and then.
  void run(const std::function<void(int64_t, int64_t, int64_t)>& progress = {});
  // One event at a time (two replays in lockstep): false once the range has ended (then finished).
  bool advance();
  // The log time of the last event replayed.
  int64_t now_utime() const { return last_utime_; }

  const std::vector<ReplayedModule>& modules() const { return modules_; }
  // Every channel a replayed module's outputs are compared on.
  const std::vector<std::string>& compared_channels() const { return compared_; }
  // Whether a recorded event is a replayed module's output (compared, not delivered). On a channel
  // shared with others (BL_COMMAND) only the module's own messages are.
  bool is_recorded_output(const std::string& channel, const std::vector<uint8_t>& bytes) const;
  // Every event that passed through (all channels), and the first and last log time replayed.
  int64_t events() const { return events_; }
  int64_t first_utime() const { return first_utime_; }
  int64_t last_utime() const { return last_utime_; }
  // Set after run().
  const RecordingReader& reader() const { return *reader_; }
  // Errors the nodes counted (rejected inputs, failed computations), per module.
  std::vector<std::pair<std::string, int64_t>> node_errors() const;

  // The configuration each module recorded first in the range and when it started (scanning from the
  // range's start, at most 60 s in). first_utime: set to the range's first event time (unchanged when the
  // range is empty).
  // first_calibration: set to the first calibration_t recorded on BL_CALIBRATION in that stretch.
  static std::vector<RecordedModule> recorded_modules(const std::vector<std::string>& sources, int64_t from_utime,
                                                      int64_t* first_utime = nullptr,
                                                      std::vector<uint8_t>* first_calibration = nullptr);

 private:
  void settle();
  void step_all();
  // The next event of the range (the one peeked at first, if any); the next one without taking it.
  bool read(runtime::LogEvent& e);
  runtime::LogEvent* peek();
  // Reads until kReadAhead events are ahead (or the log ends).
  void fill();
  // Builds the nodes whose start has come (a node that started late live misses what came before, as
  // the live one did: the projector image it never saw, the frames before it listened).
  void start_due(int64_t utime);

  std::vector<std::string> sources_;
  ReplayOptions options_;
  Sink sink_;
  std::function<void(const runtime::LogEvent&)> observer_;
  std::unique_ptr<RecordingReader> reader_;
  // Events read ahead of the one delivered (peek() looks at the next; the frames among them are offered
  // to decode_ahead_ so they decode on the second core while the nodes work).
  std::deque<runtime::LogEvent> ahead_;
  std::unique_ptr<frames::DecodeAhead> decode_ahead_;  // when a replayed module decodes frames
  const std::string frame_channel_ = channel(kImageChannel), projector_channel_ = channel(kProjectorChannel);
  std::unique_ptr<runtime::InProcessBus> hub_;
  runtime::Bus* player_ = nullptr;
  std::vector<std::unique_ptr<runtime::Node>> nodes_;  // null until the module's start
  std::vector<ReplayedModule> modules_;
  std::vector<const ModuleAdapter*> adapters_;
  std::vector<std::vector<std::string>> sets_;
  std::vector<std::string> compared_;
  const MessageDiff stamps_;  // reads an output's stamp (its utime)
  BuildContext context_;  // its scratch folder is removed with the replayer
  int64_t events_ = 0, first_utime_ = 0, last_utime_ = 0;
  bool started_ = false, ended_ = false;
};

// "prediction.annotator=paper" -> ("prediction", "annotator=paper"); "annotator=paper" -> ("", ...).
std::pair<std::string, std::string> split_set(const std::string& set);

}  // namespace bricklayer::replay
