// The .lcm parser and fingerprints against lcm-gen's generated code, and the generic decoder against
// the generated encoders: what lets the exporters handle every message type without per-type code.
#include <catch2/catch.hpp>

#include <bricklayer/block_prediction_t.hpp>
#include <bricklayer/block_t.hpp>
#include <bricklayer/calibration_t.hpp>
#include <bricklayer/collapse_preview_t.hpp>
#include <bricklayer/command_t.hpp>
#include <bricklayer/heartbeat_t.hpp>
#include <bricklayer/hint_t.hpp>
#include <bricklayer/image_t.hpp>
#include <bricklayer/prediction_t.hpp>
#include <bricklayer/projector_state_t.hpp>
#include <bricklayer/round_t.hpp>
#include <bricklayer/stack_t.hpp>
#include <bricklayer/timing_t.hpp>

#include <cmath>
#include <filesystem>
#include <limits>

#include "bricklayer/inspect/lcm_decoder.h"
#include "bricklayer/inspect/lcm_schema.h"

using namespace bricklayer;
using namespace bricklayer::inspect;

namespace {

template <typename T>
std::vector<uint8_t> encode(const T& msg) {
  std::vector<uint8_t> buf(static_cast<size_t>(msg.getEncodedSize()));
  REQUIRE(msg.encode(buf.data(), 0, static_cast<int>(buf.size())) == static_cast<int>(buf.size()));
  return buf;
}

template <typename T>
Json decode(const T& msg) {
  const LcmTypeSet& types = builtin_types();
  std::vector<uint8_t> buf = encode(msg);
  const LcmStruct* s = types.find_by_fingerprint(message_fingerprint(buf.data(), buf.size()));
  REQUIRE(s != nullptr);
  REQUIRE(s->full_name() == std::string("bricklayer.") + T::getTypeName());
  return decode_message(types, *s, buf.data(), buf.size());
}

template <typename T>
void check_fingerprint() {
  INFO(T::getTypeName());
  CHECK(builtin_types().fingerprint(std::string("bricklayer.") + T::getTypeName()) == T::getHash());
}

stack_t two_block_stack() {
  stack_t s{};
  s.utime = 1796165199842710;
  s.frame_number = 77;
  s.block_length = 1.0;
  s.block_height = 1.0 / 3;
  s.table_edge = 0;
  s.status = stack_t::STATUS_OK;
  for (int i = 0; i < 2; ++i) {
    block_t b{};
    b.id = 10 + i;
    b.row = i;
    b.x = -0.5 + 0.25 * i;
    for (int k = 0; k < 4; ++k) {
      b.corner_u[k] = 100 + k + 10 * i;
      b.corner_v[k] = 200 - k;
    }
    b.confidence = 0.875;
    s.blocks.push_back(b);
  }
  s.num_blocks = 2;
  return s;
}

}  // namespace

TEST_CASE("every built-in type's fingerprint is the one lcm-gen generated") {
  check_fingerprint<image_t>();
  check_fingerprint<block_t>();
  check_fingerprint<stack_t>();
  check_fingerprint<block_prediction_t>();
  check_fingerprint<prediction_t>();
  check_fingerprint<timing_t>();
  check_fingerprint<heartbeat_t>();
  check_fingerprint<command_t>();
  check_fingerprint<calibration_t>();
  check_fingerprint<round_t>();
  check_fingerprint<projector_state_t>();
  check_fingerprint<collapse_preview_t>();
  check_fingerprint<hint_t>();
}

TEST_CASE("every .lcm file of the tree is built in") {
  size_t files = 0;
  for (const auto& entry : std::filesystem::directory_iterator(BRICKLAYER_SOURCE_DIR "/lcmtypes"))
    if (entry.path().extension() == ".lcm") ++files;
  CHECK(builtin_types().structs().size() == files);
  const LcmStruct* stack = builtin_types().find("bricklayer.stack_t");
  REQUIRE(stack);
  CHECK(stack->members.size() == 8);
  CHECK(stack->members[2].comment.find("length unit") != std::string::npos);
  CHECK(stack->constants.size() == 3);
  CHECK(stack->comment.find("The pile of blocks") != std::string::npos);
}

TEST_CASE("the generic decoder reads what the generated encoders wrote") {
  SECTION("nested struct arrays and fixed arrays") {
    Json j = decode(two_block_stack());
    CHECK(j.at("utime").get<int64_t>() == 1796165199842710);
    CHECK(j.at("frame_number").get<int64_t>() == 77);
    CHECK(j.at("block_height").get<double>() == 1.0 / 3);
    REQUIRE(j.at("blocks").size() == 2);
    CHECK(j.at("blocks")[1].at("id").get<int64_t>() == 11);
    CHECK(j.at("blocks")[1].at("row").get<int32_t>() == 1);
    CHECK(j.at("blocks")[1].at("x").get<double>() == -0.25);
    CHECK(j.at("blocks")[1].at("corner_u")[3].get<double>() == 113);
    CHECK(j.at("blocks")[0].at("corner_v")[2].get<double>() == 198);
  }
  SECTION("strings, booleans, int8 and parallel arrays") {
    heartbeat_t h{};
    h.utime = 5;
    h.module = "vision";
    h.instance = "host:1";
    h.pid = -3;
    h.restarts = 2;
    h.status = "no frames for 5 s, \"quoted\"";
    h.value_names = {"drift_px", ""};
    h.values = {0.5, -std::numeric_limits<double>::infinity()};
    h.num_values = 2;
    Json j = decode(h);
    CHECK(j.at("module") == "vision");
    CHECK(j.at("pid").get<int32_t>() == -3);
    CHECK(j.at("status") == "no frames for 5 s, \"quoted\"");
    CHECK(j.at("value_names")[1] == "");
    CHECK(std::isinf(j.at("values")[1].get<double>()));

    prediction_t p{};
    p.status = prediction_t::STATUS_SOLVER_ERROR;
    p.balanced = true;
    p.score = -12;
    block_prediction_t b{};
    b.id = 3;
    b.state = block_prediction_t::STATE_CAUSE;
    b.accel = std::nan("");
    p.blocks = {b};
    p.num_blocks = 1;
    Json pj = decode(p);
    CHECK(pj.at("status").get<int>() == 2);
    CHECK(pj.at("balanced").get<bool>());
    CHECK(pj.at("score").get<int>() == -12);
    CHECK(pj.at("blocks")[0].at("state").get<int>() == 2);
    CHECK(std::isnan(pj.at("blocks")[0].at("accel").get<double>()));
  }
  SECTION("bytes inside a nested struct") {
    projector_state_t ps{};
    ps.frame_number = -1;
    ps.image.format = image_t::FORMAT_PNG;
    ps.image.data = {0, 255, 7};
    ps.image.size = 3;
    ps.image.source = "projection";
    Json j = decode(ps);
    CHECK(j.at("frame_number").get<int64_t>() == -1);
    REQUIRE(j.at("image").at("data").is_binary());
    const std::vector<uint8_t>& bytes = j.at("image").at("data").get_binary();
    CHECK(bytes == std::vector<uint8_t>{0, 255, 7});
  }
}

TEST_CASE("damaged messages are refused with the member's path") {
  const LcmTypeSet& types = builtin_types();
  const LcmStruct& stack = *types.find("bricklayer.stack_t");
  std::vector<uint8_t> buf = encode(two_block_stack());

  SECTION("cut short") {
    buf.resize(buf.size() - 5);  // the blocks no longer fit: refused before they are read
    CHECK_THROWS_WITH(decode_message(types, stack, buf.data(), buf.size()), Catch::Contains("cannot fit"));
    round_t r{};
    std::vector<uint8_t> rb = encode(r);
    rb.resize(rb.size() - 4);  // condition (1 byte) and 3 of best_possible
    CHECK_THROWS_WITH(decode_message(types, *types.find("bricklayer.round_t"), rb.data(), rb.size()),
                      Catch::Contains("round_t.best_possible: data ends 3 byte(s) early"));
  }
  SECTION("a hostile length is refused before allocating") {
    // num_blocks sits after utime, frame_number, 3 doubles and status: 8 + 8+8+24+1 bytes in.
    size_t at = 8 + 8 + 8 + 24 + 1;
    buf[at] = 0x7f;
    CHECK_THROWS_WITH(decode_message(types, stack, buf.data(), buf.size()), Catch::Contains("cannot fit"));
    buf[at] = 0xff;
    CHECK_THROWS_WITH(decode_message(types, stack, buf.data(), buf.size()), Catch::Contains("negative"));
  }
  SECTION("bytes left over, another type") {
    buf.push_back(0);
    CHECK_THROWS_WITH(decode_message(types, stack, buf.data(), buf.size()), Catch::Contains("left over"));
    const LcmStruct& round = *types.find("bricklayer.round_t");
    CHECK_THROWS_WITH(decode_message(types, round, buf.data(), buf.size()), Catch::Contains("fingerprint"));
  }
  SECTION("a string without its NUL") {
    heartbeat_t h{};
    h.module = "abc";
    std::vector<uint8_t> hb = encode(h);
    // module's bytes follow the fingerprint, utime and the 4-byte length: "abc\0" at 20..23.
    REQUIRE(hb[20 + 3] == 0);
    hb[23] = 'x';
    CHECK_THROWS_WITH(decode_message(types, *types.find("bricklayer.heartbeat_t"), hb.data(), hb.size()),
                      Catch::Contains("NUL"));
  }
}

TEST_CASE("the parser reads another type file and explains what is wrong") {
  auto parsed = parse_lcm(R"(package study;
// A participant's answer.
struct answer_t {
  int64_t utime;   // microseconds
  const int8_t YES = 1, NO = 0;
  int8_t choice;
  int32_t n;
  double grid[3][n];  /* a block comment */
  bricklayer.block_t picked;
})",
                          "answer_t.lcm");
  REQUIRE(parsed.size() == 1);
  const LcmStruct& s = parsed[0];
  CHECK(s.full_name() == "study.answer_t");
  CHECK(s.comment == "A participant's answer.");
  CHECK(s.constants.size() == 2);
  CHECK(s.members.at(0).comment == "microseconds");
  REQUIRE(s.members.at(3).dimensions.size() == 2);
  CHECK(s.members.at(3).dimensions[1].variable);
  CHECK(s.members.at(4).type == "bricklayer.block_t");

  CHECK_THROWS_WITH(parse_lcm("struct a { int32_t x }", "a.lcm"), Catch::Contains("a.lcm:1: expected ';'"));
  CHECK_THROWS_WITH(parse_lcm("package p;\nstruct a {\n int32_t x[-1];\n}", "a.lcm"), Catch::Contains("a.lcm:3"));
  CHECK_THROWS_WITH(parse_lcm("struct a { int32_t x; int32_t x; }", "a.lcm"), Catch::Contains("declared twice"));

  LcmTypeSet set;
  for (auto& t : parse_lcm("package p; struct a { double v[n]; int32_t n; }", "a.lcm")) set.add(t);
  CHECK_THROWS_WITH(set.finish(), Catch::Contains("earlier integer member"));
  LcmTypeSet missing;
  for (auto& t : parse_lcm("package p; struct a { p.nothing_t z; }", "a.lcm")) missing.add(t);
  CHECK_THROWS_WITH(missing.finish(), Catch::Contains("unknown type p.nothing_t"));
}
