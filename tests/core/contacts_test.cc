// Contact geometry: an overlap > 0 (even 1e-4) is a contact; ends that merely touch are not.
#include "bricklayer/core/contacts.h"

#include <catch2/catch.hpp>

using namespace bricklayer::core;

TEST_CASE("row 0 rests on the surface over [x, min(x + 1, edge)]") {
  Stack s;
  s.table_edge = 2.0;
  s.block_length = 2.0;  // normalised: edge at 0, blocks of length 1
  s.blocks = {{10, 0, 1.0}, {11, 0, 2.0}, {12, 0, -1.0}};
  const ContactGraph g = build_contacts(s);
  REQUIRE(g.supports[0].size() == 1);
  const Contact& c = g.contacts[static_cast<size_t>(g.supports[0][0])];
  CHECK(c.lower == kSurface);
  CHECK(c.left == Approx(-0.5));
  CHECK(c.right == Approx(0.0));
  CHECK(g.floating(1));  // starts exactly at the edge: touches, no contact
  REQUIRE(g.supports[2].size() == 1);
  CHECK(g.contacts[static_cast<size_t>(g.supports[2][0])].right == Approx(-0.5));  // wholly on the surface
}

TEST_CASE("an overlap of 1e-4 is a contact, touching ends are not") {
  Stack s;
  s.blocks = {{0, 0, -1.0}, {1, 1, -1.9999}, {2, 1, 0.0}, {3, 1, 2.0}};
  const ContactGraph g = build_contacts(s);
  REQUIRE(g.supports[1].size() == 1);
  const Contact& c = g.contacts[static_cast<size_t>(g.supports[1][0])];
  CHECK(c.lower == 0);
  CHECK(c.left == Approx(-1.0));
  CHECK(c.right == Approx(-0.9999));
  CHECK(g.floating(2));  // [0, 1] touches [-1, 0] at x = 0 only
  CHECK(g.floating(3));
  CHECK(g.carries[0].size() == 1);
}

TEST_CASE("a block bridging two blocks has two contact intervals, rows are sorted") {
  Stack s;
  s.blocks = {{0, 0, -0.6}, {1, 0, -1.7}, {2, 1, -1.1}};
  const ContactGraph g = build_contacts(s);
  REQUIRE(g.rows.size() == 2);
  CHECK(g.rows[0] == std::vector<int>{1, 0});
  REQUIRE(g.supports[2].size() == 2);
  const Contact& a = g.contacts[static_cast<size_t>(g.supports[2][0])];
  const Contact& b = g.contacts[static_cast<size_t>(g.supports[2][1])];
  CHECK(a.lower == 1);
  CHECK(a.left == Approx(-1.1));
  CHECK(a.right == Approx(-0.7));
  CHECK(b.lower == 0);
  CHECK(b.left == Approx(-0.6));
  CHECK(b.right == Approx(-0.1));
}
