#include "bricklayer/replay/replayer.h"

#include <algorithm>
#include <stdexcept>

#include "bricklayer/common/channels.h"
#include "bricklayer/node_config_t.hpp"
#include "bricklayer/replay/module_registry.h"
#include "bricklayer/runtime/codec.h"

namespace bricklayer::replay {
namespace {
// Between two events the clock moves in steps of this (a live node's loop ticks every 20 ms).
constexpr int64_t kStepUs = 20'000;
// How far into the range a module's recorded configuration is looked for (nodes record it every 10 s).
constexpr int64_t kConfigScanUs = 60'000'000;
}  // namespace

std::pair<std::string, std::string> split_set(const std::string& set) {
  const auto eq = set.find('=');
  const auto dot = set.find('.');
  if (dot != std::string::npos && (eq == std::string::npos || dot < eq)) return {set.substr(0, dot), set.substr(dot + 1)};
  return {"", set};
}

std::vector<std::pair<std::string, std::string>> Replayer::recorded_configs(const std::vector<std::string>& sources,
                                                                            int64_t from_utime, int64_t* first_utime) {
  std::vector<std::pair<std::string, std::string>> out;
  RecordingReader reader(sources, from_utime);
  const std::string config_channel = channel(kConfigChannel);
  runtime::LogEvent e;
  int64_t first = -1;
  while (reader.next(e)) {
    if (e.utime < from_utime) continue;
    if (first < 0) {
      first = e.utime;
      if (first_utime) *first_utime = first;
    }
    if (e.utime > first + kConfigScanUs) break;
    if (e.channel != config_channel) continue;
    const auto c = runtime::decode<node_config_t>(e.data);
    if (!c) continue;
    if (std::none_of(out.begin(), out.end(), [&](const auto& p) { return p.first == c->module; }))
      out.emplace_back(c->module, c->config_json);
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
  const auto recorded = recorded_configs(sources_, options_.from_utime, &start);
  reader_ = std::make_unique<RecordingReader>(sources_, options_.from_utime);
  // The clock starts at the range's first event, before any node reads it (its start, first heartbeat
  // and timers count from there).
  hub_ = std::make_unique<runtime::InProcessBus>(start);
  player_ = &hub_->endpoint("log");
  for (size_t i = 0; i < adapters.size(); ++i) {
    ReplayedModule m;
    m.name = adapters[i]->name;
    std::string json;
    for (const auto& [module, config] : recorded)
      if (module == m.name) json = config;
    m.config_recorded = !json.empty();
    BuiltNode built;
    try {
      built = adapters[i]->build(json, sets[i], hub_->endpoint(m.name));
    } catch (const std::invalid_argument& e) {
      throw std::invalid_argument(m.name + ": " + e.what());
    }
    m.config_json = built.config_json;
    m.notes = built.notes;
    if (!m.config_recorded) m.notes.push_back("no configuration recorded in the range: the module's defaults");
    nodes_.push_back(std::move(built.node));
    modules_.push_back(std::move(m));
    for (const auto& c : adapters[i]->compared) compared_.push_back(c);
  }
  hub_->set_tap([this](const std::string& endpoint, const std::string& ch, const uint8_t* data, size_t size, int64_t utime) {
    if (endpoint == "log") return;
    sink_(false, ch, std::vector<uint8_t>(data, data + size), utime);
  });
}

Replayer::~Replayer() = default;

void Replayer::step_all() {
  for (auto& n : nodes_) n->step(0);
}

void Replayer::settle() {
  // Each node handles what is queued (and what the others published in reply) until nothing is.
  for (int round = 0; round < 1000; ++round) {
    step_all();
    if (!hub_->pending()) return;
  }
  throw std::runtime_error("the replayed nodes keep answering each other (more than 1000 rounds for one event)");
}

bool Replayer::advance() {
  if (ended_) return false;
  runtime::LogEvent e;
  for (;;) {
    if (!reader_->next(e) || e.utime > options_.to_utime) {
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
  // Between events the nodes' loops tick, as live (timers, hint requests, heartbeats).
  for (int64_t t = hub_->now_utime() + kStepUs; t < e.utime; t += kStepUs) {
    hub_->set_utime(t);
    step_all();
    if (hub_->pending()) settle();
  }
  if (e.utime > hub_->now_utime()) hub_->set_utime(e.utime);  // recorders stamp on receipt: keep it monotone
  last_utime_ = hub_->now_utime();
  if (observer_) observer_(e);
  if (std::find(compared_.begin(), compared_.end(), e.channel) != compared_.end()) {
    sink_(true, e.channel, e.data, last_utime_);
  } else {
    player_->publish(e.channel, e.data.data(), e.data.size());
    settle();
  }
  return true;
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
  for (size_t i = 0; i < nodes_.size(); ++i) out.emplace_back(modules_[i].name, nodes_[i]->counters().errors);
  return out;
}

}  // namespace bricklayer::replay
