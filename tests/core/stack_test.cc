// Stack parsing and validation: every kind of bad input gives a one-line StackError naming the block.
#include "bricklayer/core/stack.h"

#include <catch2/catch.hpp>
#include <nlohmann/json.hpp>

using namespace bricklayer::core;

namespace {

// The error message of parse_stack(text), or "" when it parses.
std::string error_of(const std::string& text, const StackLimits& limits = {}) {
  try {
    parse_stack(text, limits);
  } catch (const StackError& e) {
    return e.what();
  }
  return "";
}

}  // namespace

TEST_CASE("a well-formed stack parses with defaults") {
  const Stack s = parse_stack(R"({"block_height": 0.5, "blocks": [{"id": 7, "row": 0, "x": -0.4}, {"row": 1, "x": -0.2}]})");
  CHECK(s.block_length == 1.0);
  CHECK(s.table_edge == 0.0);
  CHECK(s.block_height == 0.5);
  REQUIRE(s.blocks.size() == 2);
  CHECK(s.blocks[0].id == 7);
  CHECK(s.blocks[1].id == 1);  // default id: the block's index
  CHECK(s.blocks[1].row == 1);
  CHECK(s.blocks[1].x == -0.2);
}

TEST_CASE("blocks that touch in a row are valid, a floating block is valid input") {
  CHECK(error_of(R"({"blocks": [{"row": 0, "x": -2}, {"row": 0, "x": -1}, {"row": 3, "x": 5}]})").empty());
}

TEST_CASE("bad input gives a one-line error that names the block") {
  struct Case {
    const char* what;
    std::string json;
    std::vector<std::string> expected;  // substrings of the message
  };
  const Case cases[] = {
      {"overlap in a row", R"({"blocks": [{"id": 4, "row": 0, "x": -1}, {"id": 9, "row": 0, "x": -0.5}]})", {"id 9", "overlaps", "id 4", "row 0"}},
      {"tiny overlap in a row", R"({"blocks": [{"id": 4, "row": 2, "x": 0}, {"id": 9, "row": 2, "x": 0.9999}]})", {"id 9", "overlaps"}},
      {"duplicate id", R"({"blocks": [{"id": 3, "row": 0, "x": -1}, {"id": 3, "row": 1, "x": -1}]})", {"block 1", "id 3", "duplicate"}},
      {"x is a string", R"({"blocks": [{"id": 3, "row": 0, "x": "left"}]})", {"block 0", "\"x\"", "number"}},
      {"x is null (NaN written by a JSON encoder)", R"({"blocks": [{"id": 3, "row": 0, "x": null}]})", {"block 0", "\"x\""}},
      {"row is fractional", R"({"blocks": [{"row": 0.5, "x": 0}]})", {"block 0", "\"row\"", "integer"}},
      {"row is negative", R"({"blocks": [{"row": -1, "x": 0}]})", {"block 0", "\"row\""}},
      {"id is a string", R"({"blocks": [{"id": "a", "row": 0, "x": 0}]})", {"block 0", "\"id\""}},
      {"missing x", R"({"blocks": [{"id": 5, "row": 0}]})", {"block 0", "id 5", "missing \"x\""}},
      {"missing row", R"({"blocks": [{"id": 5, "x": 0}]})", {"block 0", "missing \"row\""}},
      {"unknown block key", R"({"blocks": [{"id": 5, "row": 0, "x": 0, "y": 1}]})", {"block 0", "unknown key \"y\""}},
      {"block is not an object", R"({"blocks": [[0, 0]]})", {"block 0", "object"}},
      {"blocks is not an array", R"({"blocks": {"row": 0}})", {"\"blocks\"", "array"}},
      {"no blocks key", R"({"block_length": 1})", {"missing key \"blocks\""}},
      {"stack is an array", R"([1, 2])", {"object"}},
      {"zero length", R"({"block_length": 0, "blocks": []})", {"block_length", "positive"}},
      {"negative height", R"({"block_height": -0.3, "blocks": []})", {"block_height", "positive"}},
      {"length is a string", R"({"block_length": "1", "blocks": []})", {"block_length", "number"}},
      {"overflowing number", R"({"blocks": [{"row": 0, "x": 1e999}]})", {"JSON"}},
      {"NaN literal", R"({"blocks": [{"row": 0, "x": NaN}]})", {"not valid JSON"}},
      {"unknown top-level key", R"({"block_lenght": 1, "blocks": []})", {"unknown key \"block_lenght\""}},
      {"truncated", R"({"blocks": [{"row": 0, "x": 1)", {"not valid JSON"}},
  };
  for (const Case& c : cases) {
    INFO(c.what);
    const std::string message = error_of(c.json);
    REQUIRE_FALSE(message.empty());
    CHECK(message.find('\n') == std::string::npos);
    for (const auto& part : c.expected) {
      INFO(message);
      CHECK(message.find(part) != std::string::npos);
    }
  }
}

TEST_CASE("too many blocks is an error that names the first block over the limit") {
  StackLimits limits;
  limits.max_blocks = 3;
  nlohmann::json j = {{"blocks", nlohmann::json::array()}};
  for (int i = 0; i < 4; ++i) j["blocks"].push_back({{"id", 100 + i}, {"row", i}, {"x", -0.5}});
  const std::string message = error_of(j.dump(), limits);
  CHECK(message.find("too many blocks: 4") != std::string::npos);
  CHECK(message.find("maximum is 3") != std::string::npos);
  // validate() on a Stack built in code says which block is the first one too many.
  Stack s;
  for (int i = 0; i < 4; ++i) s.blocks.push_back({100 + i, i, -0.5});
  try {
    validate(s, limits);
    FAIL("expected StackError");
  } catch (const StackError& e) {
    CHECK(std::string(e.what()).find("id 103") != std::string::npos);
  }
  // The default limit is 2000.
  CHECK(StackLimits{}.max_blocks == 2000);
}

TEST_CASE("validate rejects non-finite numbers in a Stack built in code, naming the block") {
  Stack s;
  s.blocks = {{1, 0, -0.5}, {2, 1, std::numeric_limits<double>::quiet_NaN()}};
  REQUIRE_THROWS_AS(validate(s), StackError);
  REQUIRE_THROWS_WITH(validate(s), Catch::Contains("id 2") && Catch::Contains("finite"));
  s.blocks[1].x = std::numeric_limits<double>::infinity();
  REQUIRE_THROWS_WITH(validate(s), Catch::Contains("id 2"));
  s.blocks[1].x = 0.0;
  s.table_edge = std::numeric_limits<double>::quiet_NaN();
  REQUIRE_THROWS_WITH(validate(s), Catch::Contains("table_edge"));
  s.table_edge = 0.0;
  s.block_length = 1e-310;  // positive, but (x - edge) / length overflows
  REQUIRE_THROWS_WITH(validate(s), Catch::Contains("id 1") && Catch::Contains("relative to the edge"));
}

TEST_CASE("a row above the block limit is rejected, not overflowed") {
  bricklayer::core::Stack s;
  s.blocks = {{1, 2147483647, 0.0}};
  CHECK_THROWS_WITH(bricklayer::core::validate(s), Catch::Contains("row 2147483647 is above the highest possible row"));
  s.blocks = {{1, 1999, 0.0}};  // floating at the highest row the default limit allows: valid
  CHECK_NOTHROW(bricklayer::core::validate(s));
}
