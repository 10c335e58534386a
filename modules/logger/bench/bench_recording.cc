// bricklayer-bench-recording: how many bytes an hour a recording takes, with every channel kept whole
// and camera frames under the day's frame policy (a reduced rate, full rate in windows around moments).
//
// Without --logs it plays a scenario through the real simcam, vision and prediction nodes on an
// in-process bus (the same frames, stacks and predictions the exhibit would record, faster than real
// time) and passes every message through the logger's moment detector and recording policy, exactly
// as bricklayer-logger does; with --logs it does the same with a recorded log's events. It prints the
// bytes of the full-rate recording and of the policy's, per hour and for a 10-hour day, and which
// channels they go to. Hours are extrapolated from the run's span: a scenario's own moments (its red
// blocks and collapses) set how much runs at full rate. --moment-every S adds a moment every S seconds
// (a busy exhibit: every red pile is one), and --day-hours H plays the run's events again and again,
// shifted in time, until H hours have passed through the policy, so a day under the hourly allowance
// (--max-mb-per-hour) is measured whole instead of extrapolated from minutes.
#include <algorithm>
#include <cstdio>
#include <iostream>
#include <map>
#include <memory>

#include "bricklayer/common/channels.h"
#include "bricklayer/common/flags.h"
#include "bricklayer/common/log.h"
#include "bricklayer/logger/event_writer.h"
#include "bricklayer/logger/logger_node.h"
#include "bricklayer/logger/moment_detector.h"
#include "bricklayer/logger/recording_policy.h"
#include "bricklayer/prediction/prediction_node.h"
#include "bricklayer/runtime/in_process_bus.h"
#include "bricklayer/runtime/log_file.h"
#include "bricklayer/simcam/simcam_node.h"
#include "bricklayer/vision/vision_node.h"

namespace {

using namespace bricklayer;

struct Tally {
  int64_t all_bytes = 0, kept_bytes = 0;
  std::map<std::string, int64_t> all_by_channel, kept_by_channel;
  int64_t first = -1, last = -1;
  int64_t moments = 0;
};

class Measure {
 public:
  explicit Measure(logger::FramePolicyOptions o, double moment_every_s)
      : policy_(std::move(o)), moment_every_us_(static_cast<int64_t>(moment_every_s * 1e6)) {}

  void event(int64_t utime, const std::string& ch, const uint8_t* data, size_t size) {
    if (t_.first < 0) t_.first = utime;
    t_.last = utime;
    if (moment_every_us_ > 0) {
      if (next_moment_ < 0) next_moment_ = utime + moment_every_us_;
      for (; next_moment_ <= utime; next_moment_ += moment_every_us_) {
        policy_.moment(next_moment_);
        ++t_.moments;
      }
    }
    logger::Event e{utime, ch, std::vector<uint8_t>(data, data + size)};
    const int64_t bytes = logger::EventWriter::file_size_of(e);
    t_.all_bytes += bytes;
    t_.all_by_channel[ch] += bytes;
    if (auto m = moments_.observe(ch, data, size, utime); m && logger::MomentDetector::wants_full_rate(*m)) {
      policy_.moment(utime);
      ++t_.moments;
    }
    policy_.offer(std::move(e));
    keep(policy_.release(utime));
  }

  Tally finish() {
    keep(policy_.release_all());
    return t_;
  }
  const logger::RecordingPolicy& policy() const { return policy_; }

 private:
  void keep(const std::vector<logger::Event>& out) {
    for (const auto& e : out) {
      const int64_t bytes = logger::EventWriter::file_size_of(e);
      t_.kept_bytes += bytes;
      t_.kept_by_channel[e.channel] += bytes;
    }
  }

  logger::MomentDetector moments_;
  logger::RecordingPolicy policy_;
  int64_t moment_every_us_ = 0, next_moment_ = -1;
  Tally t_;
};

struct Played {
  int64_t utime;
  std::string channel;
  std::vector<uint8_t> data;
};

// The scenario on an in-process bus: simcam -> vision -> prediction, every message kept.
void simulate(const std::string& scenario, double seconds, double fps, std::vector<Played>& out) {
  runtime::InProcessBus hub;
  simcam::SimcamConfig camera;
  camera.scenario = scenario;
  camera.fps = fps;
  camera.loop = true;
  camera.no_projector = true;
  std::vector<std::unique_ptr<runtime::Node>> nodes;
  nodes.push_back(std::make_unique<simcam::SimcamNode>(camera, hub.endpoint("simcam")));
  nodes.push_back(std::make_unique<vision::VisionNode>(vision::VisionConfig{}, hub.endpoint("vision")));
  nodes.push_back(std::make_unique<prediction::PredictionNode>(prediction::PredictionConfig{}, hub.endpoint("prediction")));
  hub.set_tap([&](const std::string&, const std::string& ch, const uint8_t* data, size_t size, int64_t utime) {
    out.push_back({utime, ch, std::vector<uint8_t>(data, data + size)});
  });
  const int64_t end = hub.now_utime() + static_cast<int64_t>(seconds * 1e6);
  while (hub.now_utime() < end) {
    hub.advance(1000);
    auto step_all = [&] {
      for (auto& n : nodes) n->step(0);
    };
    step_all();  // the nodes tick even when nothing is queued
    hub.settle(step_all);
  }
}

// The message's utime, its first field (after LCM's 8-byte fingerprint, big-endian), moved by delta.
void add_to_utime_field(std::vector<uint8_t>& data, int64_t delta) {
  uint64_t v = 0;
  for (size_t i = 8; i < 16; ++i) v = (v << 8) | data[i];
  v += static_cast<uint64_t>(delta);
  for (size_t i = 16; i-- > 8; v >>= 8) data[i] = static_cast<uint8_t>(v & 0xff);
}

double mb(int64_t bytes) { return static_cast<double>(bytes) / 1e6; }

int Main(int argc, char** argv) {
  Flags flags("bricklayer-bench-recording",
              "Bytes an hour of a recording under the day's frame policy, from a scenario played through the\n"
              "real simcam, vision and prediction nodes, or from recorded logs (--logs A,B).");
  flags.add("logs", "", "recorded logs to measure instead of a scenario, comma-separated");
  flags.add("scenario", "launch/scenarios/wall-60.json", "scenario played when no LOG is given (looped)");
  flags.add("seconds", "120", "scenario time played");
  flags.add("fps", "30", "camera frames per second");
  flags.add("rate", "2", "frames kept per second outside windows (the exhibit profiles' policy)");
  flags.add("before", "10", "full rate this long before a moment, s");
  flags.add("after", "10", "full rate this long after a moment, s");
  flags.add("max-mb-per-hour", "0", "the windows' hourly allowance (the exhibit profiles': 450); 0 = none");
  flags.add("moment-every", "0", "add a full-rate moment every this many seconds (0 = only the run's own)");
  flags.add("day-hours", "0", "play the run again and again until this many hours have passed (0 = once, extrapolated)");
  flags.add("answers", "with_frames", "with_frames (the exhibit profiles': a thinned frame's stacks, predictions, "
                                      "timings and previews go with it) or whole");
  if (!flags.parse(argc, argv)) return 0;
  log::set_level(log::parse_level("warn"));
  logger::FramePolicyOptions o;
  o.frame_channel = channel(kImageChannel);
  o.rate = flags.get_double("rate");
  o.before_s = flags.get_double("before");
  o.after_s = flags.get_double("after");
  o.max_mb_per_hour = flags.get_double("max-mb-per-hour");
  if (flags.get("answers") == "with_frames") {
    o.answer_channels = logger::answer_channels();
  } else if (flags.get("answers") != "whole") {
    throw FlagError("--answers is with_frames or whole");
  }
  Measure measure(o, flags.get_double("moment-every"));
  std::vector<Played> played;
  if (flags.get("logs").empty()) {
    simulate(flags.get("scenario"), flags.get_double("seconds"), flags.get_double("fps"), played);
  } else {
    std::string rest = flags.get("logs");
    while (!rest.empty()) {
      const auto comma = rest.find(',');
      const std::string path = rest.substr(0, comma);
      rest = comma == std::string::npos ? "" : rest.substr(comma + 1);
      runtime::LogReader reader(path);
      runtime::LogEvent e;
      while (reader.next(e)) played.push_back({e.utime, e.channel, std::move(e.data)});
    }
  }
  if (played.empty()) throw std::runtime_error("nothing recorded");
  // Each pass is shifted by the run's span plus one frame period, so the passes follow each other as
  // one recording would.
  const int64_t pass_us = played.back().utime - played.front().utime + static_cast<int64_t>(1e6 / flags.get_double("fps"));
  const int64_t day_us = static_cast<int64_t>(flags.get_double("day-hours") * 3.6e9);
  // A frame and its answers are known by their utime field (recording_policy.h), so each pass's copies
  // get their own: a later pass's answers must not be taken for an earlier pass's frame's.
  std::vector<std::string> stamped = logger::answer_channels();
  stamped.push_back(channel(kImageChannel));
  std::vector<uint8_t> data;
  for (int64_t shift = 0; shift == 0 || shift + pass_us <= day_us; shift += pass_us)
    for (const Played& p : played) {
      data = p.data;
      if (shift > 0 && data.size() >= 16 && std::find(stamped.begin(), stamped.end(), p.channel) != stamped.end())
        add_to_utime_field(data, shift);
      measure.event(p.utime + shift, p.channel, data.data(), data.size());
    }
  const Tally t = measure.finish();
  const int64_t frames_kept = measure.policy().frames_kept(), frames_thinned = measure.policy().frames_thinned();
  const double span_h = static_cast<double>(t.last - t.first) / 3.6e9;
  if (span_h <= 0) throw std::runtime_error("nothing recorded");
  std::printf("span %.1f s, %lld moments at full rate, frames kept %lld, thinned %lld (%lld of them in windows the "
              "hourly allowance could not pay for)\n",
              span_h * 3600, static_cast<long long>(t.moments), static_cast<long long>(frames_kept),
              static_cast<long long>(frames_thinned), static_cast<long long>(measure.policy().window_frames_refused()));
  std::printf("%-28s %12s %12s %14s\n", "", "MB", "MB/hour", "GB/10-hour day");
  std::printf("%-28s %12.2f %12.1f %14.2f\n", "everything at full rate", mb(t.all_bytes), mb(t.all_bytes) / span_h,
              mb(t.all_bytes) / span_h * 10 / 1000);
  std::printf("%-28s %12.2f %12.1f %14.2f\n", "the frame policy", mb(t.kept_bytes), mb(t.kept_bytes) / span_h,
              mb(t.kept_bytes) / span_h * 10 / 1000);
  const auto truth = t.kept_by_channel.find(channel(kTruthChannel));
  if (truth != t.kept_by_channel.end()) {
    // BL_TRUTH is simcam's true stack beside each frame: the exhibit's camera has none.
    const int64_t without = t.kept_bytes - truth->second;
    std::printf("%-28s %12.2f %12.1f %14.2f\n", "the policy, no BL_TRUTH", mb(without), mb(without) / span_h,
                mb(without) / span_h * 10 / 1000);
  }
  std::printf("by channel (policy, MB/hour):");
  for (const auto& [ch, bytes] : t.kept_by_channel) std::printf(" %s %.1f", ch.c_str(), mb(bytes) / span_h);
  std::printf("\n");
  return 0;
}

}  // namespace

int main(int argc, char** argv) { return bricklayer::run_main("bricklayer-bench-recording", &Main, argc, argv); }
