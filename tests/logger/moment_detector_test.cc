// The moments: red appears, a collapse (the red pile lost blocks), round start and end, the operator's mark.
#include <catch2/catch.hpp>

#include "bricklayer/command_t.hpp"
#include "bricklayer/logger/moment_detector.h"
#include "bricklayer/prediction_t.hpp"
#include "bricklayer/round_t.hpp"
#include "bricklayer/runtime/codec.h"

using namespace bricklayer;

namespace {
prediction_t prediction(int blocks, int red, int64_t frame) {
  prediction_t p{};
  p.frame_number = frame;
  p.status = prediction_t::STATUS_OK;
  p.num_blocks = blocks;
  p.blocks.resize(static_cast<size_t>(blocks));
  for (int i = 0; i < red && i < blocks; ++i) p.blocks[static_cast<size_t>(i)].state = block_prediction_t::STATE_CAUSE;
  p.balanced = red == 0;
  return p;
}
template <typename T>
std::optional<logger::Moment> see(logger::MomentDetector& d, const std::string& ch, const T& msg, int64_t t) {
  const auto b = runtime::encode(msg);
  return d.observe(ch, b.data(), b.size(), t);
}
}  // namespace

TEST_CASE("red, collapse and the end of a red episode that did not fall") {
  logger::MomentDetector d;
  CHECK_FALSE(see(d, "BL_PREDICTION", prediction(5, 0, 1), 1));
  auto m = see(d, "BL_PREDICTION", prediction(5, 1, 2), 2);
  REQUIRE(m);
  CHECK(m->kind == "red");
  CHECK(m->utime == 2);
  CHECK_FALSE(see(d, "BL_PREDICTION", prediction(5, 2, 3), 3));  // still red: no new moment
  m = see(d, "BL_PREDICTION", prediction(3, 0, 4), 4);
  REQUIRE(m);
  CHECK(m->kind == "collapse");
  CHECK(m->note.find("5 -> 3 blocks") != std::string::npos);
  REQUIRE(see(d, "BL_PREDICTION", prediction(3, 1, 5), 5));
  CHECK_FALSE(see(d, "BL_PREDICTION", prediction(3, 0, 6), 6));  // fixed by the player: no collapse
  prediction_t bad = prediction(3, 1, 7);
  bad.status = prediction_t::STATUS_INVALID_STACK;
  CHECK_FALSE(see(d, "BL_PREDICTION", bad, 7));
  const std::vector<uint8_t> garbage{1, 2, 3};
  CHECK_FALSE(d.observe("BL_PREDICTION", garbage.data(), garbage.size(), 8));
}

TEST_CASE("round start and end, and the operator's mark") {
  logger::MomentDetector d;
  round_t r{};
  r.state = round_t::STATE_IDLE;
  CHECK_FALSE(see(d, "BL_ROUND", r, 1));
  r.state = round_t::STATE_RUNNING;
  auto m = see(d, "BL_ROUND", r, 2);
  REQUIRE(m);
  CHECK(m->kind == "round_start");
  CHECK_FALSE(logger::MomentDetector::wants_full_rate(*m));
  CHECK_FALSE(see(d, "BL_ROUND", r, 3));
  r.state = round_t::STATE_ENDED;
  r.max_score = 131;
  m = see(d, "BL_ROUND", r, 4);
  REQUIRE(m);
  CHECK(m->kind == "round_end");
  CHECK(m->note.find("time up") != std::string::npos);
  CHECK(logger::MomentDetector::wants_full_rate(*m));
  command_t c{};
  c.command = command_t::SNAPSHOT;
  CHECK_FALSE(see(d, "BL_COMMAND", c, 5));
  c.command = command_t::MARK_MOMENT;
  c.argument = "visitor complaint";
  m = see(d, "BL_COMMAND", c, 6);
  REQUIRE(m);
  CHECK(m->kind == "mark");
  CHECK(m->note == "visitor complaint");
}
