// A module's main in one line: flags from the node's configuration declaration, the runtime's own
// flags, the node on the live LCM bus, run.
//
//   int main(int argc, char** argv) { return bricklayer::runtime::node_main<PredictionNode>(argc, argv); }
//
// The node type provides:
//   using Config = ...;                        a config struct with visit() (config.h)
//   static constexpr const char* kProgram;     "bricklayer-prediction"
//   static constexpr const char* kSummary;     the first paragraph of --help
//   NodeType(const Config&, runtime::Bus&);    throws std::invalid_argument for a bad configuration
// and optionally:
//   static void check(const Config&);          rules across fields; throws std::invalid_argument
//   static std::optional<int> before_bus(const Config&);  work that needs no bus (an offline mode):
//                                              an exit code ends the program there
//   static LcmBusOptions bus_options(const Config&);      how the live bus is set up (default: the
//                                              heartbeat as the loopback check)
//
// The runtime's flags: --lcm-url, --log-level, --check-config (checks the flags and every file they
// name, prints the configuration, starts nothing: the launcher's profile check), --describe-config
// (the declaration as JSON).
#pragma once

#include <iostream>
#include <optional>
#include <stdexcept>
#include <string>

#include "bricklayer/common/channels.h"
#include "bricklayer/common/flags.h"
#include "bricklayer/common/lcm_url.h"
#include "bricklayer/common/log.h"
#include "bricklayer/runtime/config.h"
#include "bricklayer/runtime/lcm_bus.h"
#include "bricklayer/runtime/node.h"

namespace bricklayer::runtime {

namespace node_main_detail {
// Declares the runtime's own flags next to the node's.
void declare_runtime_flags(Flags& flags);
// Applies --log-level, resolves and checks --lcm-url (FlagError on a bad one); returns the URL.
std::string apply_runtime_flags(const Flags& flags);
// --check-config's report: prints it and returns the exit code (0 when everything is there).
int report_check(const std::string& program, const nlohmann::json& config, const std::vector<std::string>& missing);
}  // namespace node_main_detail

template <typename NodeType>
int node_main(int argc, char** argv) {
  auto body = [](int count, char** args) -> int {
    typename NodeType::Config config;
    Flags flags(NodeType::kProgram, NodeType::kSummary);
    declare_flags(flags, config);
    node_main_detail::declare_runtime_flags(flags);
    if (!flags.parse(count, args)) return 0;
    if (flags.get_bool("describe-config")) {
      std::cout << describe(config).dump(2) << std::endl;
      return 0;
    }
    read_flags(flags, config);
    if constexpr (requires { NodeType::check(config); }) {
      try {
        NodeType::check(config);
      } catch (const std::invalid_argument& e) {
        throw FlagError(e.what());
      }
    }
    const std::string url = node_main_detail::apply_runtime_flags(flags);
    if (flags.get_bool("check-config"))
      return node_main_detail::report_check(NodeType::kProgram, to_json(config), missing_paths(config));
    if constexpr (requires { NodeType::before_bus(config); }) {
      if (const std::optional<int> code = NodeType::before_bus(config)) return *code;
    }
    Node::install_signal_handlers();
    LcmBusOptions bus_options{channel(kHeartbeatChannel)};
    if constexpr (requires { NodeType::bus_options(config); }) bus_options = NodeType::bus_options(config);
    LcmBus bus(url, bus_options);
    std::optional<NodeType> node;
    try {
      node.emplace(config, bus);
    } catch (const std::invalid_argument& e) {
      throw FlagError(e.what());
    }
    node->set_config(NodeType::kProgram, to_json(config).dump());
    return node->run();
  };
  // run_main takes a plain function: the lambda has no captures.
  return run_main(NodeType::kProgram, +body, argc, argv);
}

}  // namespace bricklayer::runtime
