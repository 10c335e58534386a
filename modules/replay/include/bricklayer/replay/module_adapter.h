// A module as replay runs it: its real node, built from the configuration it recorded on BL_CONFIG
// (node_config_t), with a replay's overrides (--set name=value) on top, on a bus the replay drives.
// Any node type with a Config that visit()s its fields fits (node_adapter<NodeType>); the registry
// (module_registry.h) lists the modules of this build.
#pragma once

#include <algorithm>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "bricklayer/runtime/bus.h"
#include "bricklayer/runtime/config.h"
#include "bricklayer/runtime/node.h"

namespace bricklayer::replay {

struct BuiltNode {
  std::unique_ptr<runtime::Node> node;
  std::string config_json;           // the configuration it runs with (as live: before the replay's own settings)
  std::vector<std::string> notes;    // recorded keys this build does not know (left out), replay settings, ...
};

// What a replay gives a module's build besides its configuration.
struct BuildContext {
  std::string scratch_dir;  // a folder of this replay's own (files a node writes go here, never the live ones)
  // The first calibration_t recorded on BL_CALIBRATION in the range (encoded; empty when none): the
  // calibration file a serving node loaded live, which is not in the log itself.
  std::vector<uint8_t> recorded_calibration;
};

struct ModuleAdapter {
  std::string name;      // its heartbeat_t.module / node_config_t.module: "prediction"
  std::string program;   // "bricklayer-prediction"
  std::vector<std::string> compared;  // its output channels, compared with the recorded ones
  // Whether a recorded event on one of the compared channels is this module's output (not delivered,
  // compared) rather than another's message on a shared channel (delivered): BL_COMMAND carries the
  // calibration's pattern commands and the operator's. Empty: every event on a compared channel is.
  std::function<bool(const std::string& channel, const std::vector<uint8_t>& bytes)> owns;
  // Fields of its output types that are run-to-run (never compared while it is replayed), with why.
  std::vector<std::string> ignored;
  // Its outputs are stamped with its own clock at a loop tick (timers, refreshes), not with the input
  // they answer: the replay ticks it at the time of each of its recorded outputs as well, so a tick
  // the live node published on is a tick of the replay too.
  bool ticks_at_outputs = false;
  // With ticks_at_outputs: the fields of its outputs that depend on when the tick fell (the stamp, a
  // countdown read at the tick). On a log recorded live its outputs pair with the replayed ones by
  // nearest stamp time (output_matcher.h), and those pairs are compared without these fields.
  std::vector<std::string> tick_fields;
  // With ticks_at_outputs: the channels it reads. Two outputs paired by nearest time are compared only
  // when none of these was delivered between their stamps (else each tick saw other inputs).
  std::vector<std::string> tick_inputs;
  // It decodes camera frames (BL_IMAGE) and projector images (BL_PROJECTOR): the replay then decodes
  // them ahead on a second thread (frames/decode_ahead.h).
  bool decodes_frames = false;
  // recorded_json: the node_config_t.config_json recorded ("" = none: the defaults). sets: "name=value".
  // Throws std::invalid_argument for an override that names no field or breaks its rule.
  std::function<BuiltNode(const std::string& recorded_json, const std::vector<std::string>& sets, runtime::Bus& bus,
                          const BuildContext& context)>
      build;
  // The configuration's declaration (runtime::describe), for --help and errors.
  std::function<std::string()> describe;

  bool is_output(const std::string& channel, const std::vector<uint8_t>& bytes) const {
    if (std::find(compared.begin(), compared.end(), channel) == compared.end()) return false;
    return !owns || owns(channel, bytes);
  }
};

// How a module runs in a replay beyond its recorded configuration (node_adapter's options).
template <typename Config>
struct AdapterOptions {
  std::function<bool(const std::string&, const std::vector<uint8_t>&)> owns;
  std::vector<std::string> ignored;
  bool ticks_at_outputs = false;
  std::vector<std::string> tick_fields;
  std::vector<std::string> tick_inputs;
  bool decodes_frames = false;
  // Settings a replay must force (no screen, no sound, no live files): applied after the recorded
  // configuration and --set; returns the notes that say what was changed.
  std::function<std::vector<std::string>(Config&, const BuildContext&)> replay_settings;
};

template <typename NodeType>
ModuleAdapter node_adapter(std::string name, std::vector<std::string> compared,
                           AdapterOptions<typename NodeType::Config> options = {}) {
  ModuleAdapter a;
  a.name = std::move(name);
  a.program = NodeType::kProgram;
  a.compared = std::move(compared);
  a.owns = options.owns;
  a.ignored = options.ignored;
  a.ticks_at_outputs = options.ticks_at_outputs;
  a.tick_fields = options.tick_fields;
  a.tick_inputs = options.tick_inputs;
  a.decodes_frames = options.decodes_frames;
  a.build = [replay_settings = options.replay_settings](const std::string& recorded, const std::vector<std::string>& sets,
                                                        runtime::Bus& bus, const BuildContext& context) {
    typename NodeType::Config config;
    BuiltNode built;
    if (!recorded.empty()) {
      nlohmann::json j = nlohmann::json::parse(recorded, nullptr, false);
      if (j.is_discarded() || !j.is_object()) throw std::invalid_argument("the recorded configuration is not a JSON object");
      // A log recorded by another build may name fields this one lacks: they are left out, and said.
      std::vector<std::string> known;
      for (const auto& d : runtime::describe(config)) known.push_back(d.at("name").template get<std::string>());
      for (auto it = j.begin(); it != j.end();) {
        if (std::find(known.begin(), known.end(), it.key()) == known.end()) {
          built.notes.push_back("recorded field '" + it.key() + "' is not in this build's configuration: left out");
          it = j.erase(it);
        } else {
          ++it;
        }
      }
      runtime::from_json(j, config);
    }
    for (const auto& s : sets) runtime::set_from_text(s, config);
    // What it runs with as live would (the configuration --update records); the replay's own
    // settings on top are said in the notes.
    built.config_json = runtime::to_json(config).dump();
    if (replay_settings)
      for (auto& n : replay_settings(config, context)) built.notes.push_back(std::move(n));
    built.node = std::make_unique<NodeType>(config, bus);
    built.node->set_config(NodeType::kProgram, built.config_json);
    return built;
  };
  a.describe = [] { return runtime::describe(typename NodeType::Config{}).dump(); };
  return a;
}

}  // namespace bricklayer::replay
