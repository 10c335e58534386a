// NETNS: malformed bytes, wrong-fingerprint and oversized messages on BL_STACK are counted errors in
// bricklayer-prediction's heartbeat, and the process keeps answering good stacks.
#include <catch2/catch.hpp>

#include "bricklayer/launcher/process.h"
#include "bricklayer/prediction/prediction_logic.h"
#include "bricklayer/prediction/sample_stacks.h"
#include "bricklayer/prediction_t.hpp"
#include "bricklayer/stack_t.hpp"
#include "bus_test_util.h"

using namespace bricklayer;
using namespace std::chrono_literals;

TEST_CASE("bad messages on BL_STACK are counted errors and the prediction process keeps running") {
  launcher::SpawnOptions opts;
  opts.env = {std::string("LCM_DEFAULT_URL=") + test::kTestUrl};
  auto proc = launcher::Process::spawn(
      {test::bin("bricklayer-prediction"), "--max-blocks", "100", "--log-level", "error"}, opts);
  test::Listener bus;
  REQUIRE(bus.ok());
  bus.listen(channel(kPredictionChannel));
  bus.listen(channel(kHeartbeatChannel));
  heartbeat_t hb{};
  REQUIRE(bus.pump_until([&] { return bus.last_heartbeat("prediction", hb) && hb.pid == proc.pid(); }, 10s));

  const std::string ch = channel(kStackChannel);
  // 1. Malformed bytes.
  const char garbage[] = "\x01\x02 definitely not a stack_t";
  bus.lcm().publish(ch, garbage, sizeof(garbage));
  // 2. A valid stack_t, truncated.
  auto truncated = test::encode(prediction::sample_stack(10, 1, 1, 1));
  truncated.resize(truncated.size() / 2);
  bus.lcm().publish(ch, truncated.data(), static_cast<unsigned>(truncated.size()));
  // 3. Another type (wrong fingerprint).
  heartbeat_t other{};
  other.module = "impostor";
  bus.lcm().publish(ch, &other);
  // 4. Oversized: a well-formed 300-block stack is larger than --max-blocks=100 allows.
  stack_t big = prediction::sample_stack(300, 2, 2, 2);
  REQUIRE(static_cast<size_t>(big.getEncodedSize()) > prediction::max_stack_message_bytes(100));
  bus.lcm().publish(ch, &big);
  // 5. Oversized garbage, fragmented by LCM (100 KB).
  std::vector<uint8_t> huge(100000, 0xAB);
  bus.lcm().publish(ch, huge.data(), static_cast<unsigned>(huge.size()));
  bus.pump(50ms);  // let the process read the fragments before more traffic arrives
  // 6. Decodes and fits, but has more blocks than --max-blocks: answered with STATUS_INVALID_STACK.
  stack_t over = prediction::sample_stack(101, 3, 3, 3);
  REQUIRE(static_cast<size_t>(over.getEncodedSize()) <= prediction::max_stack_message_bytes(100));
  bus.lcm().publish(ch, &over);
  REQUIRE(bus.pump_until([&] { return bus.count(channel(kPredictionChannel)) == 1; }, 3s));
  prediction_t invalid{};
  REQUIRE(test::decode(bus.on(channel(kPredictionChannel)).back().bytes, invalid));
  CHECK(invalid.frame_number == 3);
  CHECK(invalid.status == prediction_t::STATUS_INVALID_STACK);
  CHECK(invalid.error.find("--max-blocks") != std::string::npos);

  // Still alive and answering.
  stack_t good = prediction::sample_stack(12, 4, 4, 4);
  bus.lcm().publish(ch, &good);
  REQUIRE(bus.pump_until([&] { return bus.count(channel(kPredictionChannel)) == 2; }, 3s));
  prediction_t answer{};
  REQUIRE(test::decode(bus.on(channel(kPredictionChannel)).back().bytes, answer));
  CHECK(answer.frame_number == 4);
  CHECK(answer.status == prediction_t::STATUS_OK);
  CHECK(proc.running());

  // The heartbeat counts all six bad inputs as errors: five rejected before decoding finished, one
  // rejected stack. Received counts the two that decoded (the 101-block one and the good one).
  REQUIRE(bus.pump_until([&] { return bus.last_heartbeat("prediction", hb) && hb.published == 2; }, 3s));
  bus.pump_until([&] { return bus.last_heartbeat("prediction", hb) && hb.errors >= 6; }, 2500ms);
  CHECK(hb.errors == 6);
  CHECK(hb.received == 2);
  CHECK(hb.pid == proc.pid());
}
