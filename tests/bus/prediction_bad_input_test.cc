// NETNS: malformed bytes, wrong-fingerprint and oversized messages on the wire (BL_STACK) are counted
// errors in bricklayer-prediction's heartbeat, and the process keeps answering good stacks.
#include <catch2/catch.hpp>

#include "bricklayer/common/channels.h"
#include "bricklayer/prediction/prediction_logic.h"
#include "bricklayer/prediction/sample_stacks.h"
#include "bricklayer/prediction_t.hpp"
#include "bricklayer/runtime/lcm_bus.h"
#include "bricklayer/stack_t.hpp"
#include "harness/program.h"
#include "harness/recorder.h"

using namespace bricklayer;
using namespace std::chrono_literals;

namespace {
constexpr const char* kUrl = "udpm://239.255.76.67:7667?ttl=0";
}

TEST_CASE("bad messages on BL_STACK are counted errors and the prediction process keeps running") {
  runtime::LcmBus bus(kUrl);
  auto rec = harness::Recorder::live(bus, {channel(kPredictionChannel), channel(kHeartbeatChannel)});
  harness::Program proc("bricklayer-prediction", {"--max-blocks", "100", "--log-level", "error"},
                        harness::ProgramOptions{{std::string("LCM_DEFAULT_URL=") + kUrl}, ""});
  REQUIRE(rec.wait_for_heartbeat("prediction", [&](const heartbeat_t& hb) { return hb.pid == proc.pid(); }, 10s));

  const std::string ch = channel(kStackChannel);
  auto send = [&](const std::vector<uint8_t>& bytes) { REQUIRE(bus.publish(ch, bytes.data(), bytes.size())); };
  // 1. Malformed bytes.
  const std::string garbage = "\x01\x02 definitely not a stack_t";
  send(std::vector<uint8_t>(garbage.begin(), garbage.end()));
  // 2. A valid stack_t, truncated.
  auto truncated = runtime::encode(prediction::sample_stack(10, 1, 1, 1));
  truncated.resize(truncated.size() / 2);
  send(truncated);
  // 3. Another type (wrong fingerprint).
  heartbeat_t other{};
  other.module = "impostor";
  send(runtime::encode(other));
  // 4. Oversized: a well-formed 300-block stack is larger than --max-blocks=100 allows.
  const stack_t big = prediction::sample_stack(300, 2, 2, 2);
  REQUIRE(static_cast<size_t>(big.getEncodedSize()) > prediction::max_stack_message_bytes(100));
  send(runtime::encode(big));
  // 5. Oversized garbage, fragmented by LCM (100 KB).
  send(std::vector<uint8_t>(100000, 0xAB));
  rec.pump_for(50ms);  // let the process read the fragments before more traffic arrives
  // 6. Decodes and fits, but has more blocks than --max-blocks: answered with STATUS_INVALID_STACK.
  const stack_t over = prediction::sample_stack(101, 3, 3, 3);
  REQUIRE(static_cast<size_t>(over.getEncodedSize()) <= prediction::max_stack_message_bytes(100));
  send(runtime::encode(over));
  auto invalid = rec.wait_for<prediction_t>(channel(kPredictionChannel), {}, 3s);
  REQUIRE(invalid);
  CHECK(invalid->frame_number == 3);
  CHECK(invalid->status == prediction_t::STATUS_INVALID_STACK);
  CHECK(invalid->error.find("--max-blocks") != std::string::npos);

  // Still alive and answering.
  send(runtime::encode(prediction::sample_stack(12, 4, 4, 4)));
  auto answer = rec.wait_for<prediction_t>(channel(kPredictionChannel), [](const prediction_t& p) { return p.frame_number == 4; }, 3s);
  REQUIRE(answer);
  CHECK(answer->status == prediction_t::STATUS_OK);
  CHECK(proc.running());

  // The heartbeat counts all six bad inputs as errors: five rejected before decoding finished, one
  // rejected stack. Received counts the two that decoded (the 101-block one and the good one).
  auto hb = rec.wait_for_heartbeat("prediction", [](const heartbeat_t& h) { return h.published == 2 && h.errors >= 6; }, 4s);
  REQUIRE(hb);
  CHECK(hb->errors == 6);
  CHECK(hb->received == 2);
  CHECK(hb->pid == proc.pid());
}
