#include "bricklayer/board/board_geometry.h"

#include <catch2/catch.hpp>

using namespace bricklayer;

TEST_CASE("board geometry loads every key and converts both ways") {
  auto g = parse_board_geometry(
      R"({"edge_x_px": 300, "surface_y_px": 400, "block_length_px": 80, "block_height_px": 26.5})");
  CHECK(g.edge_x_px == 300);
  CHECK(g.to_px_x(0.5) == Approx(340));
  CHECK(g.from_px_x(g.to_px_x(-1.25)) == Approx(-1.25));
  CHECK(g.row_top_px(0) == Approx(373.5));
}

TEST_CASE("board geometry names a missing, unknown or bad key") {
  CHECK_THROWS_WITH(parse_board_geometry(R"({"edge_x_px": 1, "surface_y_px": 2, "block_length_px": 3})"),
                    Catch::Contains("missing key 'block_height_px'"));
  CHECK_THROWS_WITH(parse_board_geometry(
                        R"({"edge_x_px":1,"surface_y_px":2,"block_length_px":3,"block_height_px":1,"zoom":2})"),
                    Catch::Contains("unknown key 'zoom'"));
  CHECK_THROWS_WITH(parse_board_geometry(
                        R"({"edge_x_px":1,"surface_y_px":2,"block_length_px":-3,"block_height_px":1})"),
                    Catch::Contains("must be positive"));
  CHECK_THROWS_WITH(parse_board_geometry("not json"), Catch::Contains("not valid JSON"));
}
