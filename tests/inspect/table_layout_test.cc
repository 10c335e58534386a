// CSV rows from message definitions: one row per block for stacks and predictions (and one for an
// empty pile), units in the column names, wall-clock twins of every time, quoting per RFC 4180.
#include <catch2/catch.hpp>

#include <algorithm>

#include "bricklayer/inspect/json_schema.h"
#include "bricklayer/inspect/log_source.h"
#include "bricklayer/inspect/table_layout.h"
#include "bricklayer/inspect/units.h"
#include "bricklayer/inspect/wall_clock.h"

using namespace bricklayer::inspect;

namespace {

size_t column(const TableLayout& t, const std::string& name) {
  auto it = std::find(t.header().begin(), t.header().end(), name);
  REQUIRE(it != t.header().end());
  return static_cast<size_t>(it - t.header().begin());
}

Json block(int64_t id, double x) {
  return Json{{"id", id}, {"row", 0}, {"x", x}, {"corner_u", {1, 2, 3, 4}}, {"corner_v", {5, 6, 7, 8.5}}, {"confidence", 1.0},
              {"x_uncertainty", 0.0015}};
}

}  // namespace

TEST_CASE("stacks: one row per block, an empty pile one row, units and UTC in the header") {
  const LcmTypeSet& types = builtin_types();
  TableLayout t(types, *types.find("bricklayer.stack_t"));
  CHECK(t.has_items());
  for (const char* name : {"event", "log_utime_us", "log_utc", "item_index", "utime_us", "utime_utc",
                           "table_edge_block_lengths", "blocks.x_block_lengths", "blocks.corner_u_3_px", "blocks.confidence"})
    CHECK(std::count(t.header().begin(), t.header().end(), name) == 1);
  LogEvent e;
  e.number = 42;
  e.timestamp_us = 1796165199915800;
  Json stack = {{"utime", 1796165199842710}, {"frame_number", 3}, {"block_length", 1.0}, {"block_height", 0.25},
                {"table_edge", 0.0}, {"status", 0}, {"num_blocks", 2}, {"blocks", {block(7, -0.5), block(8, 0.1)}}};
  auto rows = t.rows(e, stack);
  REQUIRE(rows.size() == 2);
  CHECK(rows[1][column(t, "item_index")] == "1");
  CHECK(rows[1][column(t, "blocks.id")] == "8");
  CHECK(rows[1][column(t, "blocks.x_block_lengths")] == "0.1");
  CHECK(rows[0][column(t, "blocks.corner_v_3_px")] == "8.5");
  CHECK(rows[0][column(t, "utime_utc")] == "2026-12-01 22:46:39.842710");
  CHECK(rows[0][column(t, "log_utc")] == "2026-12-01 22:46:39.915800");
  CHECK(rows[0][column(t, "event")] == "42");
  for (const auto& r : rows) CHECK(r.size() == t.header().size());

  stack["num_blocks"] = 0;
  stack["blocks"] = Json::array();
  rows = t.rows(e, stack);
  REQUIRE(rows.size() == 1);
  CHECK(rows[0][column(t, "item_index")] == "");
  CHECK(rows[0][column(t, "blocks.id")] == "");
  CHECK(rows[0][column(t, "frame_number")] == "3");
}

TEST_CASE("other layouts: a type without arrays, bytes left out, nested structs, JSON cells") {
  const LcmTypeSet& types = builtin_types();
  TableLayout round(types, *types.find("bricklayer.round_t"));
  CHECK_FALSE(round.has_items());
  CHECK(std::count(round.header().begin(), round.header().end(), "max_score_points") == 1);
  CHECK(std::count(round.header().begin(), round.header().end(), "remaining_ms") == 1);

  TableLayout image(types, *types.find("bricklayer.image_t"));
  CHECK_FALSE(image.has_items());  // its only array is the bytes, which stay out
  CHECK(std::count(image.header().begin(), image.header().end(), "data") == 0);
  CHECK(std::count(image.header().begin(), image.header().end(), "size_bytes") == 1);

  TableLayout projector(types, *types.find("bricklayer.projector_state_t"));
  CHECK(std::count(projector.header().begin(), projector.header().end(), "image.width_px") == 1);
  CHECK(std::count(projector.header().begin(), projector.header().end(), "image.utime_utc") == 1);

  TableLayout preview(types, *types.find("bricklayer.collapse_preview_t"));
  LogEvent e;
  Json p = {{"utime", 1}, {"frame_number", 2}, {"num_blocks", 2}, {"block_ids", {4, 5}}, {"end_state", {3, 0}}, {"num_frames", 1},
            {"time_s", {0.5}}, {"num_values", 6}, {"poses", {1, 2, 3, 4, 5, 6.25}}};
  auto rows = preview.rows(e, p);
  REQUIRE(rows.size() == 2);  // one per block id: the first variable-length array
  CHECK(rows[1][column(preview, "block_ids")] == "5");
  CHECK(rows[0][column(preview, "end_state")] == "3");  // an array as long as block_ids: one per row
  CHECK(rows[0][column(preview, "poses")] == "[1,2,3,4,5,6.25]");
  CHECK(rows[0][column(preview, "time_s")] == "[0.5]");
}

TEST_CASE("cells and quoting") {
  CHECK(cell_text(Json(0.1)) == "0.1");
  CHECK(cell_text(Json(1.0 / 3)) == "0.3333333333333333");
  CHECK(cell_text(Json(std::nan(""))) == "nan");
  CHECK(cell_text(Json(-INFINITY)) == "-inf");
  CHECK(cell_text(Json(true)) == "true");
  CHECK(cell_text(Json(int64_t{-9007199254740993})) == "-9007199254740993");
  CHECK(csv_quote("plain") == "plain");
  CHECK(csv_quote("a,b") == "\"a,b\"");
  CHECK(csv_quote("say \"hi\"\n") == "\"say \"\"hi\"\"\n\"");
  CHECK(utc_text(0) == "1970-01-01 00:00:00.000000");
  CHECK(utc_text(-1) == "1969-12-31 23:59:59.999999");
  CHECK(column_name("bricklayer.block_t", "x") == "x_block_lengths");
  CHECK(column_name("study.anything_t", "started_utime") == "started_utime_us");
  CHECK(column_name("bricklayer.timing_t", "elapsed_us") == "elapsed_us");
}

TEST_CASE("JSON Schemas follow the definitions, and the MCAP JSON form drops only image bytes") {
  const LcmTypeSet& types = builtin_types();
  Json s = json_schema(types, *types.find("bricklayer.projector_state_t"));
  CHECK(s.at("title") == "bricklayer.projector_state_t");
  CHECK(s.at("additionalProperties") == false);
  const Json& image = s.at("properties").at("image");
  CHECK_FALSE(image.at("properties").contains("data"));
  CHECK(image.at("properties").at("width").at("maximum") == INT32_MAX);
  Json stack = json_schema(types, *types.find("bricklayer.stack_t"));
  const Json& corner = stack.at("properties").at("blocks").at("items").at("properties").at("corner_u");
  CHECK(corner.at("minItems") == 4);
  CHECK(corner.at("maxItems") == 4);
  CHECK_THAT(stack.at("description").get<std::string>(), Catch::Contains("STATUS_NO_BOARD = 2"));
  CHECK_THAT(corner.at("description").get<std::string>(), Catch::Contains("[unit: px]"));

  Json msg = {{"utime", 1}, {"frame_number", 2}, {"command_sequence", -1}, {"mode", 0},
              {"image", {{"utime", 1}, {"frame_number", 0}, {"width", 2}, {"height", 1}, {"format", 2},
                         {"source", "p"}, {"size", 2}, {"data", Json::binary({1, 2})}}}};
  Json m = mcap_json(types, *types.find("bricklayer.projector_state_t"), msg);
  CHECK_FALSE(m.at("image").contains("data"));
  CHECK(m.at("image").at("size") == 2);
}
