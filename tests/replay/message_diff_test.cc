// MessageDiff: any message compared field by field from the .lcm definitions; keys; ignored fields.
#include <catch2/catch.hpp>

#include "bricklayer/prediction_t.hpp"
#include "bricklayer/replay/message_diff.h"
#include "bricklayer/runtime/codec.h"
#include "bricklayer/timing_t.hpp"

using namespace bricklayer;

namespace {
prediction_t prediction() {
  prediction_t p{};
  p.utime = 1234;
  p.frame_number = 77;
  p.annotator = "exact";
  p.num_blocks = 3;
  p.blocks.resize(3);
  for (int i = 0; i < 3; ++i) p.blocks[static_cast<size_t>(i)].id = i;
  return p;
}
}  // namespace

TEST_CASE("two predictions differ in the fields named, an ignored field is left out") {
  const replay::MessageDiff diff({"prediction_t.blocks[].accel", "timing_t"});
  prediction_t a = prediction(), b = prediction();
  CHECK(diff.differences(runtime::encode(a), runtime::encode(b)).empty());
  b.blocks[1].state = block_prediction_t::STATE_CAUSE;
  b.score = 131;
  b.blocks[2].accel = -0.5;  // ignored
  const auto d = diff.differences(runtime::encode(a), runtime::encode(b));
  REQUIRE(d.size() == 2);
  CHECK(d[0].path == "score");
  CHECK(d[0].b == "131");
  CHECK(d[1].path == "blocks[1].state");
  CHECK(replay::MessageDiff::describe(d, "log", "replay") == "score: 0 (log) vs 131 (replay); blocks[1].state: 0 (log) vs 2 (replay)");
  b = prediction();
  b.num_blocks = 2;
  b.blocks.resize(2);
  const auto sized = diff.differences(runtime::encode(a), runtime::encode(b));
  REQUIRE_FALSE(sized.empty());
  CHECK(sized[0].path == "num_blocks");
  timing_t t1{}, t2{};
  t2.elapsed_us = 99;
  CHECK(diff.differences(runtime::encode(t1), runtime::encode(t2)).empty());  // a whole type ignored
  CHECK(diff.ignores_type("timing_t"));
}

TEST_CASE("a message's key is its utime and frame number, and other bytes are no message") {
  const replay::MessageDiff diff;
  const auto bytes = runtime::encode(prediction());
  const auto key = diff.key("BL_PREDICTION", bytes.data(), bytes.size());
  REQUIRE(key);
  CHECK(key->utime == 1234);
  CHECK(key->frame_number == 77);
  CHECK(diff.type_of(bytes.data(), bytes.size()) == "prediction_t");
  const std::vector<uint8_t> junk{1, 2, 3, 4, 5, 6, 7, 8, 9};
  CHECK_FALSE(diff.key("X", junk.data(), junk.size()));
  const auto d = diff.differences(bytes, junk);
  REQUIRE(d.size() == 1);
  CHECK(d[0].b == "not a known message");
  std::vector<uint8_t> cut(bytes.begin(), bytes.end() - 5);
  const auto broken = diff.differences(bytes, cut);
  REQUIRE(broken.size() == 1);
  CHECK(broken[0].b.find("does not decode") == 0);
}
