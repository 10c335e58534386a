// bricklayer-bench-projection: prediction received -> frame presented, in bricklayer-projection's own
// node (ProjectionNode), headless (SDL's offscreen driver, software renderer, no vsync), on the
// runtime's in-process bus so only the projection's own work is timed: decode, scene update,
// drawing the blocks, HUD and miniature into the projector-size frame, and presenting it.
// Each iteration publishes a stack and its prediction (the colours change every frame) and steps the
// loop once. projector_state_t capture (at most --state-hz) runs after the present, as in the process.
#include <algorithm>
#include <cstdio>
#include <vector>

#include "bricklayer/common/flags.h"
#include "bricklayer/common/log.h"
#include "bricklayer/projection/projection_node.h"
#include "bricklayer/runtime/codec.h"
#include "bricklayer/runtime/in_process_bus.h"

namespace {

int Main(int argc, char** argv) {
  using namespace bricklayer;
  Flags flags("bricklayer-bench-projection",
              "Prediction received -> frame presented (median, p99), headless offscreen driver.");
  flags.add("blocks", "60", "blocks in the stack");
  flags.add("frames", "1000", "timed frames (after 50 warm-up frames)");
  flags.add("width", "1024", "projector width");
  flags.add("height", "768", "projector height");
  flags.add("state-hz", "15", "projector_state_t rate (as in the process)");
  if (!flags.parse(argc, argv)) return 0;
  log::set_level(log::Level::kWarn);
  const int blocks = static_cast<int>(flags.get_int("blocks"));
  const int frames = static_cast<int>(flags.get_int("frames"));
  if (blocks < 1 || frames < 1) throw FlagError("--blocks and --frames must be positive");

  projection::ProjectionConfig config;
  config.headless = true;
  config.width = static_cast<int>(flags.get_int("width"));
  config.height = static_cast<int>(flags.get_int("height"));
  config.state_hz = flags.get_double("state-hz");
  config.mute = true;
  runtime::InProcessBus hub;
  runtime::Bus& peer = hub.endpoint("bench");
  projection::ProjectionNode node(config, hub.endpoint("projection"));
  auto send = [&peer](const char* channel, const auto& msg) {
    const std::vector<uint8_t> bytes = runtime::encode(msg);
    peer.publish(channel, bytes.data(), bytes.size());
  };

  // A wall: rows of 3 blocks, staggered by half a block, 1 block over the edge.
  stack_t stack{};
  stack.block_length = 1;
  stack.block_height = 1.0 / 3.0;
  stack.table_edge = 0;
  stack.status = stack_t::STATUS_OK;
  prediction_t prediction{};
  prediction.status = prediction_t::STATUS_OK;
  prediction.annotator = "exact";
  prediction.solver = "bench";
  for (int i = 0; i < blocks; ++i) {
    block_t b{};
    b.id = i;
    b.row = i / 3;
    b.x = -2.0 + (i % 3) + ((b.row % 2) ? 0.5 : 0.0);
    b.confidence = 1;
    stack.blocks.push_back(b);
    block_prediction_t bp{};
    bp.id = i;
    prediction.blocks.push_back(bp);
  }
  stack.num_blocks = blocks;
  prediction.num_blocks = blocks;

  const int total = frames + 50;
  for (int f = 0; f < total; ++f) {
    stack.frame_number = f;
    stack.utime = f * 33333;
    prediction.frame_number = f;
    prediction.utime = stack.utime;
    for (int i = 0; i < blocks; ++i) prediction.blocks[i].state = static_cast<int8_t>((i + f) % 3);
    prediction.balanced = false;
    send("BL_STACK", stack);
    send("BL_PREDICTION", prediction);
    node.step(0);
    hub.advance(33333);  // the camera's frame period on the node's clock (state rate, staleness)
  }
  std::vector<int64_t> lat = node.present_latencies_us();
  if (lat.size() < static_cast<size_t>(total)) {
    std::fprintf(stderr, "only %zu of %d predictions were presented\n", lat.size(), total);
    return 1;
  }
  lat.erase(lat.begin(), lat.begin() + 50);
  std::sort(lat.begin(), lat.end());
  auto at = [&](double q) { return lat[std::min(lat.size() - 1, static_cast<size_t>(q * (lat.size() - 1) + 0.5))] / 1000.0; };
  std::printf("projection, %d blocks, %dx%d, offscreen driver (software renderer), %zu frames\n", blocks,
              config.width, config.height, lat.size());
  std::printf("prediction received -> frame presented: median %.3f ms, p99 %.3f ms, max %.3f ms\n", at(0.5),
              at(0.99), lat.back() / 1000.0);
  return 0;
}

}  // namespace

int main(int argc, char** argv) { return bricklayer::run_main("bricklayer-bench-projection", &Main, argc, argv); }
