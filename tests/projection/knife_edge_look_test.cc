// knife_edge_look: which blocks are outlined, the pulse, the margin text.
#include "bricklayer/projection/knife_edge_look.h"

#include <catch2/catch.hpp>

#include <cmath>

using namespace bricklayer;
using namespace bricklayer::projection;

TEST_CASE("the margin as players read it") {
  CHECK(margin_text(2.0) == "2.0 mm to spare");
  CHECK(margin_text(-0.3) == "0.3 mm too far");
  CHECK(margin_text(0.01) == "on the edge");
  CHECK(margin_text(-0.04) == "on the edge");
  CHECK(margin_text(3.75) == "more than 3.7 mm to spare");
  CHECK(margin_text(-3.75) == "more than 3.7 mm too far");
  CHECK(margin_text(std::nan("")).empty());
}

TEST_CASE("only a knife edge outlines its deciding blocks, in a slow red pulse, no prediction, no look") {
  prediction_t p{};
  p.status = prediction_t::STATUS_OK;
  p.verdict = prediction_t::VERDICT_KNIFE_EDGE;
  for (int64_t id : {3, 4, 5}) {
    block_prediction_t b{};
    b.id = id;
    b.deciding = id != 4;
    p.blocks.push_back(b);
  }
  p.num_blocks = 3;
  p.uncertainty = 0.003;
  p.margin_mm = 0.12;
  KnifeEdgeLook a = knife_edge_look(&p, 0);
  CHECK(a.knife_edge);
  CHECK(a.outlined == std::vector<int64_t>{3, 5});
  CHECK(a.margin_text == "0.1 mm to spare");
  const KnifeEdgeLook b = knife_edge_look(&p, kKnifeEdgePulseMs / 2);
  CHECK(a.outline.r == 102);  // 40 % at the start of a pulse ...
  CHECK(b.outline.r == 255);  // ... 100 % half way
  CHECK(knife_edge_look(&p, kKnifeEdgePulseMs).outline.r == a.outline.r);
  CHECK(a.outline.b == 0);
  p.verdict = prediction_t::VERDICT_FALLS;
  p.margin_mm = -1.0;
  const KnifeEdgeLook falls = knife_edge_look(&p, 0);
  CHECK_FALSE(falls.knife_edge);
  CHECK(falls.outlined.empty());
  CHECK(falls.margin_text == "1.0 mm too far");
  p.uncertainty = 0.0;  // judged without uncertainty (an older recording): no text
  CHECK(knife_edge_look(&p, 0).margin_text.empty());
  p.status = prediction_t::STATUS_INVALID_STACK;
  CHECK_FALSE(knife_edge_look(&p, 0).knife_edge);
  CHECK_FALSE(knife_edge_look(nullptr, 0).knife_edge);
}
