#include "bricklayer/logger/logger_node.h"

#include <pthread.h>
#include <signal.h>

#include <cmath>
#include <cstdio>
#include <ctime>
#include <optional>

#include "bricklayer/common/channels.h"
#include "bricklayer/common/log.h"
#include "bricklayer/image_t.hpp"
#include "bricklayer/logger/log_series.h"
#include "bricklayer/logger/udp_socket_stats.h"

namespace bricklayer::logger {
namespace {

// SIGHUP (start a new file) is blocked in every thread and collected in tick(): a handler would
// interrupt the bus's poll.
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

WriterOptions writer_options(const LoggerConfig& c) {
  WriterOptions w;
  w.base = c.strftime ? expand_strftime(c.file, static_cast<long long>(std::time(nullptr))) : c.file;
  w.rotate = c.rotate;
  w.split_bytes = static_cast<int64_t>(std::llround(c.split_mb * 1024 * 1024));
  w.flush_ms = c.flush_ms;
  w.max_unwritten_bytes = static_cast<int64_t>(std::llround(c.max_unwritten_mb * 1024 * 1024));
  w.budget_bytes = static_cast<int64_t>(std::llround(c.budget_mb * 1024 * 1024));
  w.min_free_bytes = static_cast<int64_t>(std::llround(c.min_free_mb * 1024 * 1024));
  w.series_prefix = c.series;
  w.index = !c.no_index;
  return w;
}

FramePolicyOptions frame_policy(const LoggerConfig& c) {
  FramePolicyOptions f;
  f.frame_channel = channel(kImageChannel);
  f.rate = c.frame_rate;
  f.before_s = c.full_rate_before_s;
  f.after_s = c.full_rate_after_s;
  if (c.answers_with_frames) f.answer_channels = answer_channels();
  f.max_mb_per_hour = c.max_mb_per_hour;
  // The delay line shares the unwritten bound: together they never hold more than twice it.
  f.max_held_bytes = static_cast<int64_t>(std::llround(c.max_unwritten_mb * 1024 * 1024));
  return f;
}

MomentChannels moment_channels() {
  MomentChannels m;
  m.prediction = channel(kPredictionChannel);
  m.round = channel(kRoundChannel);
  m.command = channel(kCommandChannel);
  return m;
}

std::string mb(int64_t bytes) {
  char text[32];
  std::snprintf(text, sizeof text, "%.1f MB", static_cast<double>(bytes) / (1024.0 * 1024.0));
  return text;
}

}  // namespace

std::vector<std::string> answer_channels() {
  return {channel(kStackChannel), channel(kPredictionChannel), channel(kTimingChannel), channel(kPreviewChannel),
          channel(kTruthChannel)};
}

std::string LoggerConfig::regex_rule(const std::string& pattern) {
  try {
    std::regex check(pattern);
    return "";
  } catch (const std::regex_error& e) {
    return "'" + pattern + "' is not a valid regular expression: " + e.what();
  }
}

void LoggerNode::check(const Config& c) {
  if (c.budget_mb > 0 && c.split_mb > 0 && 2 * c.split_mb > c.budget_mb)
    throw std::invalid_argument("--split-mb must be at most half of --budget-mb (the open file is never deleted), got " +
                                runtime::config_detail::to_text(c.split_mb) + " and " +
                                runtime::config_detail::to_text(c.budget_mb));
  if (c.budget_mb > 0 && c.split_mb == 0)
    throw std::invalid_argument("--budget-mb needs --split-mb (the budget deletes whole files, never the open one)");
  if (c.max_mb_per_hour > 0 && c.frame_rate == 0)
    throw std::invalid_argument("--max-mb-per-hour needs --frame-rate (it bounds the windows of full-rate frames, "
                                "and without a reduced rate every frame is kept)");
}

runtime::LcmBusOptions LoggerNode::bus_options(const Config& config) {
  block_sighup();  // before LCM and the writer start their threads, which inherit the mask
  runtime::LcmBusOptions o;
  o.loopback_channel = channel(kHeartbeatChannel);
  o.lcm_queue_capacity = config.queue_capacity;
  return o;
}

LoggerNode::LoggerNode(const Config& config, runtime::Bus& bus)
    : Node("logger", bus),
      channels_(config.channels),
      has_exclude_(!config.exclude.empty()),
      exclude_(config.exclude.empty() ? "^$" : config.exclude),
      image_channel_(channel(kImageChannel)),
      port_(udpm_port(bus.describe())),
      moments_(moment_channels()),
      policy_(frame_policy(config)),
      budget_bytes_(static_cast<int64_t>(std::llround(config.budget_mb * 1024 * 1024))) {
  runtime::validate(config);
  check(config);
  writer_ = std::make_unique<EventWriter>(writer_options(config));
  // One subscription sees everything; --channels / --exclude narrow it in wanted() (the same full
  // match), so what is skipped is counted. The queue only holds one burst: the handler copies.
  subscribe_bytes(".*", runtime::QueuePolicy::keep(size_t{1} << 20), [this](const runtime::Received& r) { on_message(r); },
                  size_t{1} << 30);
  const int64_t recv_buf_bytes = static_cast<int64_t>(std::llround(config.recv_buf_mb * 1024 * 1024));
  if (port_ > 0) {
    const UdpSocketStats st = raise_receive_buffer(port_, recv_buf_bytes);
    rcvbuf_bytes_ = st.rcvbuf_bytes;
    if (st.sockets == 0)
      log::warn("found no socket of this process on UDP port ", port_, ": kernel drops cannot be counted");
    else if (st.rcvbuf_bytes < recv_buf_bytes)
      log::warn("the kernel gave a ", st.rcvbuf_bytes, "-byte receive buffer of the ", recv_buf_bytes,
                " asked (capped by net.core.rmem_max; run as root or: sysctl -w net.core.rmem_max=", recv_buf_bytes, ")");
  }
  log::info("logging ", bus.describe(), " into ", writer_->stats().current_file, " (receive buffer ", rcvbuf_bytes_,
            " bytes, queue ", config.queue_capacity, " messages / ", static_cast<int64_t>(config.max_unwritten_mb), " MB)");
  update_figures();
}

LoggerNode::~LoggerNode() { writer_->stop(); }

bool LoggerNode::wanted(const std::string& ch) {
  if (auto it = wanted_.find(ch); it != wanted_.end()) return it->second;
  const bool w = std::regex_match(ch, channels_) && !(has_exclude_ && std::regex_match(ch, exclude_));
  if (wanted_.size() < 4096) wanted_.emplace(ch, w);  // bounded: channel names come from the network
  return w;
}

void LoggerNode::on_message(const runtime::Received& r) {
  if (!wanted(r.channel)) {
    ++excluded_;
    return;
  }
  Event e;
  e.utime = r.utime;
  e.channel = r.channel;
  e.data.assign(r.data, r.data + r.size);
  if (std::optional<Moment> m = moments_.observe(r.channel, r.data, r.size, r.utime)) {
    ++moments_seen_;
    if (MomentDetector::wants_full_rate(*m)) policy_.moment(m->utime, m->kind == "mark");
    log::info("moment: ", m->kind, m->note.empty() ? "" : " (" + m->note + ")");
    writer_->note(std::move(*m));
  }
  if (r.channel == image_channel_) observe_sequence(e);
  if (policy_.thins())
    policy_.offer(std::move(e));
  else
    writer_->push(std::move(e));
}

void LoggerNode::observe_sequence(const Event& e) {
  // Numbers that skip reveal messages lost before they reached us. Checked on arrival, before the
  // recording policy: the frames it thins were received, and counting them would report a thinned day as
  // lost frames (a dropped write is counted by the writer instead).
  image_t img{};
  if (img.decode(e.data.data(), 0, static_cast<int>(e.data.size())) < 0) return;  // logged as bytes anyway
  if (const int64_t skipped = sequence_.observe(e.channel, img.source, img.frame_number); skipped > 0)
    log::warn(e.channel, " from ", img.source, ": ", skipped, " frame(s) before ", img.frame_number,
              " never reached the logger");
  gaps_ = sequence_.missing();
  source_restarts_ = sequence_.restarts();
}

void LoggerNode::update_figures() {
  const WriterStats w = writer_->stats();
  runtime::NodeCounters& c = own_counters();
  c.published = w.written;
  c.dropped = w.dropped;
  c.errors = w.write_errors;
  if (port_ > 0 && now() >= next_socket_check_utime_) {
    const UdpSocketStats st = udp_socket_stats(port_);
    kernel_drops_ = st.drops;
    rcvbuf_bytes_ = st.rcvbuf_bytes;
    next_socket_check_utime_ = now() + 500'000;
  }
  set_value("kernel_drops", static_cast<double>(kernel_drops_));
  set_value("sequence_gaps", static_cast<double>(gaps_.load()));
  set_value("source_restarts", static_cast<double>(source_restarts_.load()));
  set_value("excluded", static_cast<double>(excluded_));
  set_value("bytes_written", static_cast<double>(w.bytes));
  set_value("queue_bytes", static_cast<double>(w.queued_bytes));
  set_value("queue_peak_bytes", static_cast<double>(w.peak_queued_bytes));
  set_value("files", static_cast<double>(w.files));
  set_value("rcvbuf_bytes", static_cast<double>(rcvbuf_bytes_));
  set_value("lost", static_cast<double>(w.lost));
  set_value("deleted_files", static_cast<double>(w.deleted_files));
  set_value("deleted_bytes", static_cast<double>(w.deleted_bytes));
  set_value("series_bytes", static_cast<double>(w.series_bytes));
  set_value("free_bytes", static_cast<double>(w.free_bytes));
  set_value("budget_bytes", static_cast<double>(budget_bytes_));
  set_value("frames_kept", static_cast<double>(policy_.frames_kept()));
  set_value("frames_thinned", static_cast<double>(policy_.frames_thinned()));
  set_value("answers_thinned", static_cast<double>(policy_.answers_thinned()));
  set_value("window_frames_refused", static_cast<double>(policy_.window_frames_refused()));
  set_value("held_bytes", static_cast<double>(policy_.held_bytes()));
  set_value("moments", static_cast<double>(moments_seen_));
  const int64_t lost = w.dropped + kernel_drops_ + gaps_.load();
  if (lost > 0 || w.write_errors > 0 || w.lost > 0) {
    set_status("LOSING: " + std::to_string(w.dropped) + " queue-full drops, " + std::to_string(kernel_drops_) +
               " kernel drops, " + std::to_string(gaps_.load()) + " sequence gaps, " + std::to_string(w.write_errors) +
               " write errors, " + std::to_string(w.lost) + " events not kept (disk full or over budget)" +
               (w.current_file.empty() ? "; no file open" : ""));
  } else {
    set_status("ok");
  }
}

void LoggerNode::tick() {
  for (Event& e : policy_.release(now())) writer_->push(std::move(e));
  update_figures();
  if (take_sighup()) writer_->request_new_file();
}

void LoggerNode::before_stop() {
  // Take what the bus still holds (until it is quiet for 50 ms, at most 1 s), then write, flush and
  // sync it all.
  const int64_t until = now() + 1'000'000;
  for (int64_t before = -1; now() < until && counters().received != before;) {
    before = counters().received;
    if (!step(50)) break;
  }
  for (Event& e : policy_.release_all()) writer_->push(std::move(e));
  const std::string last_file = writer_->stats().current_file;  // stop() closes it and forgets its name
  writer_->stop();
  update_figures();
  const WriterStats w = writer_->stats();
  log::info("stopped: ", counters().received, " received, ", w.written, " written (", w.bytes, " bytes, ", w.files,
            " file(s), last ", last_file.empty() ? std::string("none") : last_file, "), ", w.dropped, " dropped (queue full), ", kernel_drops_,
            " kernel drops, ", gaps_.load(), " sequence gaps, ", w.write_errors, " write errors, ", w.lost,
            " not kept (disk full or over budget), ", excluded_, " excluded; ", w.deleted_files, " old file(s) deleted (",
            mb(w.deleted_bytes), "), the series holds ", mb(w.series_bytes), ", ", mb(w.free_bytes), " free; frames ",
            policy_.frames_kept(), " kept, ", policy_.frames_thinned(), " thinned (and ",
            policy_.answers_thinned(), " of their answers; ", policy_.window_frames_refused(),
            " in windows the hourly allowance could not pay for); ", moments_seen_, " moments");
}

}  // namespace bricklayer::logger
