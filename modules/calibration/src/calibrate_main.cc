// bricklayer-calibrate: camera-to-projector registration, colour mixing, drift check and board scale as
// a process on the bus (CalibrateNode). node_main's steps (flags and --help from the configuration's
// declaration, --check-config, the node on a live LcmBus that waits for an unreachable bus instead of
// exiting), except that the exit code is the node's: 1 for a rejected calibration, 3 for drift.
#include "bricklayer/calibration/calibrate_node.h"
#include "bricklayer/runtime/node_main.h"

namespace bricklayer {
namespace {

using calibration::CalibrateNode;

int Main(int argc, char** argv) {
  CalibrateNode::Config config;
  Flags flags(CalibrateNode::kProgram, CalibrateNode::kSummary);
  runtime::declare_flags(flags, config);
  runtime::node_main_detail::declare_runtime_flags(flags);
  if (!flags.parse(argc, argv)) return 0;
  if (flags.get_bool("describe-config")) {
    std::cout << runtime::describe(config).dump(2) << std::endl;
    return 0;
  }
  runtime::read_flags(flags, config);
  try {
    CalibrateNode::check(config);
  } catch (const std::invalid_argument& e) {
    throw FlagError(e.what());
  }
  const std::string url = runtime::node_main_detail::apply_runtime_flags(flags);
  if (flags.get_bool("check-config"))
    return runtime::node_main_detail::report_check(CalibrateNode::kProgram, runtime::to_json(config),
                                                   runtime::missing_paths(config));
  if (const std::optional<int> code = CalibrateNode::before_bus(config)) return *code;
  runtime::Node::install_signal_handlers();
  runtime::LcmBus bus(url, runtime::LcmBusOptions{channel(kHeartbeatChannel)});
  std::optional<CalibrateNode> node;
  try {
    node.emplace(config, bus);
  } catch (const std::invalid_argument& e) {
    throw FlagError(e.what());
  }
  node->set_config(CalibrateNode::kProgram, runtime::to_json(config).dump());
  const int code = node->run();
  // A stop by SIGINT/SIGTERM before the run finished exits as run() says (0), as every node does.
  return node->finished() ? node->exit_code() : code;
}

}  // namespace
}  // namespace bricklayer

int main(int argc, char** argv) { return bricklayer::run_main("bricklayer-calibrate", &bricklayer::Main, argc, argv); }
