#include "bricklayer/replay/replayer.h"

#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <filesystem>
#include <stdexcept>

#include "bricklayer/common/channels.h"
#include "bricklayer/heartbeat_t.hpp"
#include "bricklayer/image_t.hpp"
#include "bricklayer/projector_state_t.hpp"
#include "bricklayer/node_config_t.hpp"
#include "bricklayer/replay/module_registry.h"
#include "bricklayer/runtime/codec.h"

namespace bricklayer::replay {
namespace {
// Between two events the clock moves in steps of this (a live node's loop ticks every 20 ms).
constexpr int64_t kStepUs = 20'000;
// How far into the range a module's recorded configuration is looked for (nodes record it every 10 s).
constexpr int64_t kConfigScanUs = 60'000'000;
// A module that started at most this long before the log's first event starts the replay's clock.
constexpr int64_t kEarlyStartUs = 1'000'000;
}  // namespace

std::pair<std::string, std::string> split_set(const std::string& set) {
  const auto eq = set.find('=');
  const auto dot = set.find('.');
  if (dot != std::string::npos && (eq == std::string::npos || dot < eq)) return {set.substr(0, dot), set.substr(dot + 1)};
  return {"", set};
}

std::vector<RecordedModule> Replayer::recorded_modules(const std::vector<std::string>& sources, int64_t from_utime,
                                                      int64_t* first_utime, std::vector<uint8_t>* first_calibration) {
  std::vector<RecordedModule> out;
  auto entry = [&out](const std::string& module) -> RecordedModule& {
    for (auto& m : out)
      if (m.module == module) return m;
    out.push_back({module, "", -1});
    return out.back();
  };
  RecordingReader reader(sources, from_utime);
  const std::string config_channel = channel(kConfigChannel), heartbeat_channel = channel(kHeartbeatChannel),
                    calibration_channel = channel(kCalibrationChannel);
  runtime::LogEvent e;
  int64_t first = -1;
  while (reader.next(e)) {
    if (e.utime < from_utime) continue;
    if (first < 0) {
      first = e.utime;
      if (first_utime) *first_utime = first;
    }
    if (e.utime > first + kConfigScanUs) break;
    if (e.channel == calibration_channel && first_calibration && first_calibration->empty()) {
      *first_calibration = e.data;
    } else if (e.channel == config_channel) {
      const auto c = runtime::decode<node_config_t>(e.data);
      if (c && entry(c->module).config_json.empty()) entry(c->module).config_json = c->config_json;
    } else if (e.channel == heartbeat_channel) {
      const auto h = runtime::decode<heartbeat_t>(e.data);
      if (h && entry(h->module).start_utime < 0) entry(h->module).start_utime = h->utime - h->uptime_us;
    }
  }
  return out;
}

Replayer::Replayer(std::vector<std::string> sources, ReplayOptions options, Sink sink)
    : sources_(std::move(sources)), options_(std::move(options)), sink_(std::move(sink)) {
  if (options_.modules.empty()) throw std::invalid_argument("no module to replay (available: " + replayable_names() + ")");
  std::vector<const ModuleAdapter*> adapters;
  for (const auto& name : options_.modules) {
    const ModuleAdapter& a = module_named(name);
    if (std::find(adapters.begin(), adapters.end(), &a) != adapters.end())
      throw std::invalid_argument("module '" + name + "' is named twice");
    adapters.push_back(&a);
  }
  // Every --set goes to the module it names, or to each module that has the field.
  std::vector<std::vector<std::string>> sets(adapters.size());
  for (const auto& s : options_.sets) {
    auto [module, assignment] = split_set(s);
    bool used = false;
    for (size_t i = 0; i < adapters.size(); ++i) {
      if (!module.empty() && module != adapters[i]->name) continue;
      const std::string field = assignment.substr(0, assignment.find('='));
      const bool has = adapters[i]->describe().find("\"name\":\"" + field + "\"") != std::string::npos;
      if (module.empty() && !has) continue;
      sets[i].push_back(assignment);
      used = true;
    }
    if (!used)
      throw std::invalid_argument("--set " + s + ": no replayed module (" + [&] {
        std::string n;
        for (const auto* a : adapters) n += (n.empty() ? "" : ", ") + a->name;
        return n;
      }() + ") has that field");
  }
  int64_t start = 0;
  const auto recorded = recorded_modules(sources_, options_.from_utime, &start, &context_.recorded_calibration);
  // A folder of the replay's own for what a node writes (a calibration run's file), never the live ones.
  static std::atomic<int> replays{0};
  const auto scratch = std::filesystem::temp_directory_path() /
                       ("bricklayer-replay-" + std::to_string(::getpid()) + "-" + std::to_string(replays++));
  std::filesystem::create_directories(scratch);
  context_.scratch_dir = scratch.string();
  reader_ = std::make_unique<RecordingReader>(sources_, options_.from_utime);
  // The clock starts at the range's first event, before any node reads it (its start, first heartbeat
  // and timers count from there); or when a replayed module started, if that was just before the
  // first event (a log whose first events are the nodes' first step): its timers (staleness, rounds,
  // animations) count from its own start, as live.
  if (options_.from_utime == 0)
    for (const auto& r : recorded)
      if (std::find(options_.modules.begin(), options_.modules.end(), r.module) != options_.modules.end() &&
          r.start_utime >= 0 && r.start_utime < start && start - r.start_utime <= kEarlyStartUs)
        start = r.start_utime;
  hub_ = std::make_unique<runtime::InProcessBus>(start);
  player_ = &hub_->endpoint("log");
  adapters_ = adapters;
  sets_ = sets;
  if (std::any_of(adapters_.begin(), adapters_.end(), [](const ModuleAdapter* a) { return a->decodes_frames; })) {
    decode_ahead_ = std::make_unique<frames::DecodeAhead>();
    frames::DecodeAhead::install(decode_ahead_.get());
  }
  for (size_t i = 0; i < adapters.size(); ++i) {
    ReplayedModule m;
    m.name = adapters[i]->name;
    m.start_utime = start;
    for (const auto& r : recorded) {
      if (r.module != m.name) continue;
      m.config_recorded = !r.config_json.empty();
      m.config_json = r.config_json;  // replaced by what it runs with when it starts
      if (r.start_utime > start) m.start_utime = r.start_utime;
    }
    if (!m.config_recorded) m.notes.push_back("no configuration recorded in the range: the module's defaults");
    if (m.start_utime > start)
      m.notes.push_back("started " + std::to_string((m.start_utime - start) / 1000) + " ms into the range, as recorded");
    modules_.push_back(std::move(m));
    nodes_.emplace_back();
    for (const auto& c : adapters[i]->compared) compared_.push_back(c);
  }
  // Nodes up at the range's start are built now, so a bad configuration is an error before anything
  // runs (and the scratch folder goes with the replay that failed to start).
  try {
    start_due(start);
  } catch (...) {
    nodes_.clear();
    std::error_code ec;
    std::filesystem::remove_all(context_.scratch_dir, ec);
    throw;
  }
  hub_->set_tap([this](const std::string& endpoint, const std::string& ch, const uint8_t* data, size_t size, int64_t utime) {
    if (endpoint == "log") return;
    sink_(false, ch, std::vector<uint8_t>(data, data + size), utime);
  });
}

Replayer::~Replayer() {
  nodes_.clear();
  std::error_code ec;
  if (!context_.scratch_dir.empty()) std::filesystem::remove_all(context_.scratch_dir, ec);
}

bool Replayer::is_recorded_output(const std::string& ch, const std::vector<uint8_t>& bytes) const {
  for (const auto* a : adapters_)
    if (a->is_output(ch, bytes)) return true;
  return false;
}

void Replayer::start_due(int64_t utime) {
  for (size_t i = 0; i < modules_.size(); ++i) {
    if (nodes_[i] || modules_[i].start_utime > utime) continue;
    ReplayedModule& m = modules_[i];
    BuiltNode built;
    try {
      built = adapters_[i]->build(m.config_recorded ? m.config_json : std::string(), sets_[i], hub_->endpoint(m.name),
                                   context_);
    } catch (const std::invalid_argument& e) {
      throw std::invalid_argument(m.name + ": " + e.what());
    }
    m.config_json = built.config_json;
    m.notes.insert(m.notes.end(), built.notes.begin(), built.notes.end());
    nodes_[i] = std::move(built.node);
  }
}

void Replayer::step_all() {
  for (auto& n : nodes_)
    if (n) n->step(0);
}

void Replayer::settle() {
  // Each node handles what is queued (and what the others published in reply) until nothing is; one
  // round always, so the nodes tick.
  step_all();
  hub_->settle([this] { step_all(); }, 1000);
}

bool Replayer::advance() {
  if (ended_) return false;
  runtime::LogEvent e;
  for (;;) {
    if (!read(e) || e.utime > options_.to_utime) {
      settle();
      ended_ = true;
      return false;
    }
    if (e.utime >= options_.from_utime) break;
  }
  ++events_;
  if (!started_) {
    first_utime_ = e.utime;
    started_ = true;
  }
  // Between events the nodes' loops tick, as live (timers, hint requests, heartbeats); and at the
  // stamp of each recorded output of a module that stamps them at its tick, which live (on LCM) is the
  // node's clock when it published, a little before the logger received it: ticked there, the replayed
  // node reads the same clock (the round's time left, the animation's phase) on the inputs it had.
  std::vector<int64_t> ticks;
  for (int64_t t = hub_->now_utime() + kStepUs; t < e.utime; t += kStepUs) ticks.push_back(t);
  auto stamped_tick = [&](const runtime::LogEvent& x) {
    for (const auto* a : adapters_) {
      if (!a->ticks_at_outputs || !a->is_output(x.channel, x.data)) continue;
      const auto key = stamps_.key(x.channel, x.data.data(), x.data.size());
      if (key && key->utime > hub_->now_utime() && key->utime < e.utime) ticks.push_back(key->utime);
    }
  };
  stamped_tick(e);
  for (const auto& x : ahead_) stamped_tick(x);
  std::sort(ticks.begin(), ticks.end());
  ticks.erase(std::unique(ticks.begin(), ticks.end()), ticks.end());
  for (const int64_t t : ticks) {
    hub_->set_utime(t);
    start_due(t);
    settle();
  }
  if (e.utime > hub_->now_utime()) hub_->set_utime(e.utime);  // recorders stamp on receipt: keep it monotone
  start_due(hub_->now_utime());
  last_utime_ = hub_->now_utime();
  if (observer_) observer_(e);
  const ModuleAdapter* owner = nullptr;
  for (const auto* a : adapters_)
    if (a->is_output(e.channel, e.data)) owner = a;
  if (owner) {
    sink_(true, e.channel, e.data, last_utime_);
    // The live node ticked here (its output says so): a timer due now fires now in the replay too.
    if (owner->ticks_at_outputs) settle();
  } else {
    player_->publish(e.channel, e.data.data(), e.data.size());
    // Messages of one instant reach a live node together (one wait, then its handlers, then its
    // tick): the next event at the same time is delivered before the nodes handle and tick.
    runtime::LogEvent* next = peek();
    const bool same_instant = next && next->utime == e.utime && next->utime <= options_.to_utime &&
                              !is_recorded_output(next->channel, next->data);
    if (!same_instant) settle();
  }
  return true;
}

bool Replayer::read(runtime::LogEvent& e) {
  fill();
  if (ahead_.empty()) return false;
  e = std::move(ahead_.front());
  ahead_.pop_front();
  return true;
}

runtime::LogEvent* Replayer::peek() {
  fill();
  return ahead_.empty() ? nullptr : &ahead_.front();
}

void Replayer::fill() {
  // About eight camera frames ahead at the demo's mix of channels (seven other events a frame).
  constexpr size_t kReadAhead = 64;
  while (ahead_.size() < kReadAhead) {
    runtime::LogEvent e;
    if (!reader_->next(e)) return;
    if (decode_ahead_) {
      if (e.channel == frame_channel_) {
        if (auto image = runtime::decode<image_t>(e.data)) decode_ahead_->offer(std::move(*image));
      } else if (e.channel == projector_channel_) {
        if (auto state = runtime::decode<projector_state_t>(e.data)) decode_ahead_->offer(std::move(state->image));
      }
    }
    ahead_.push_back(std::move(e));
  }
}

void Replayer::run(const std::function<void(int64_t, int64_t, int64_t)>& progress) {
  int64_t since_progress = 0;
  while (advance()) {
    if (progress && ++since_progress >= 2000) {
      since_progress = 0;
      progress(reader_->done_bytes(), reader_->total_bytes(), last_utime_);
    }
  }
  if (progress) progress(reader_->total_bytes(), reader_->total_bytes(), last_utime_);
}

std::vector<std::pair<std::string, int64_t>> Replayer::node_errors() const {
  std::vector<std::pair<std::string, int64_t>> out;
  for (size_t i = 0; i < nodes_.size(); ++i)
    out.emplace_back(modules_[i].name, nodes_[i] ? nodes_[i]->counters().errors : 0);
  return out;
}

}  // namespace bricklayer::replay
