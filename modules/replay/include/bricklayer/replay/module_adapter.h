// A module as replay runs it: its real node, built from the configuration it recorded on BL_CONFIG
// (node_config_t), with a replay's overrides (--set name=value) on top, on a bus the replay drives.
// Any node type with a Config that visit()s its fields fits (node_adapter<NodeType>); the registry
// (module_registry.h) lists the modules of this build.
#pragma once

#include <algorithm>
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
  std::string config_json;           // the configuration it runs with
  std::vector<std::string> notes;    // recorded keys this build does not know (left out), ...
};

struct ModuleAdapter {
  std::string name;      // its heartbeat_t.module / node_config_t.module: "prediction"
  std::string program;   // "bricklayer-prediction"
  std::vector<std::string> compared;  // its output channels, compared with the recorded ones
  // recorded_json: the node_config_t.config_json recorded ("" = none: the defaults). sets: "name=value".
  // Throws std::invalid_argument for an override that names no field or breaks its rule.
  std::function<BuiltNode(const std::string& recorded_json, const std::vector<std::string>& sets, runtime::Bus& bus)> build;
  // The configuration's declaration (runtime::describe), for --help and errors.
  std::function<std::string()> describe;
};

template <typename NodeType>
ModuleAdapter node_adapter(std::string name, std::vector<std::string> compared) {
  ModuleAdapter a;
  a.name = std::move(name);
  a.program = NodeType::kProgram;
  a.compared = std::move(compared);
  a.build = [](const std::string& recorded, const std::vector<std::string>& sets, runtime::Bus& bus) {
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
    built.config_json = runtime::to_json(config).dump();
    built.node = std::make_unique<NodeType>(config, bus);
    built.node->set_config(NodeType::kProgram, built.config_json);
    return built;
  };
  a.describe = [] { return runtime::describe(typename NodeType::Config{}).dump(); };
  return a;
}

}  // namespace bricklayer::replay
