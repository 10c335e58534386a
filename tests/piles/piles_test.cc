// The piles library: every generator gives the piles it gave before it moved here (tests and
// benchmarks compare figures across commits by seed), pinned by a digest of every field of a few
// piles; the same seed gives the same pile; the fixtures are the optimal stacks of tests/data.
#include <catch2/catch.hpp>

#include <cstring>
#include <string>

#include "bricklayer/core/predict.h"
#include "bricklayer/piles/chaotic_pile.h"
#include "bricklayer/piles/known.h"
#include "bricklayer/piles/pile_in_view.h"
#include "bricklayer/piles/player_pile.h"
#include "bricklayer/piles/random_pile.h"
#include "bricklayer/piles/walls.h"

using namespace bricklayer;

namespace {

// FNV-1a over the sizes and every block's id, row and x (bit patterns: a change in the last bit shows).
uint64_t digest(const core::Stack& s) {
  uint64_t h = 1469598103934665603ull;
  auto mix = [&](uint64_t v) {
    for (int i = 0; i < 8; ++i) {
      h ^= (v >> (8 * i)) & 0xff;
      h *= 1099511628211ull;
    }
  };
  auto mix_double = [&](double d) {
    uint64_t v;
    std::memcpy(&v, &d, sizeof v);
    mix(v);
  };
  mix_double(s.block_length);
  mix_double(s.block_height);
  mix_double(s.table_edge);
  mix(s.blocks.size());
  for (const auto& b : s.blocks) {
    mix(static_cast<uint64_t>(b.id));
    mix(static_cast<uint64_t>(b.row));
    mix_double(b.x);
  }
  return h;
}

struct Pinned {
  std::string name;
  core::Stack pile;
  size_t blocks;
  uint64_t digest;
  double last_x;  // the last block's left end, readable when a digest differs
};

piles::PileOptions tight_rows() {
  piles::PileOptions o;
  o.blocks = 40;
  o.min_gap = 0;
  o.max_gap = 0.3;
  return o;
}

}  // namespace

TEST_CASE("every generator gives the piles it gave before it moved into the piles library") {
  // Digests taken from core/generate.h, simcam/piles.h, tests/core/piles.h, reliability/frames.h and
  // planner/piles.h before the move.
  const Pinned pinned[] = {
      {"harmonic_stack(5)", piles::harmonic_stack(5), 5, 0xa04352afe9f31df2ull, 0.14166666666666661},
      {"harmonic_stack(12, 0.25)", piles::harmonic_stack(12, 0.25), 12, 0x9dfb97fc70b4b5a1ull, 0.55160533910533904},
      {"player_pile(25, 7)", piles::player_pile(25, 7), 25, 0x6bc448400bfee85bull, -3.4053095959078985},
      {"player_pile(60, 60007)", piles::player_pile(60, 60007), 60, 0x630a5181d2f6e062ull, -2.5068994602812249},
      {"random_pile(3, {.blocks = 25})", piles::random_pile(3, {.blocks = 25}), 25, 0xa93f6ac2a0b2dc75ull, 1.1121923368200795},
      {"random_pile(11, 40 blocks, gaps 0..0.3)", piles::random_pile(11, tight_rows()), 40, 0x2b3b9462b9a67a4aull, -2.3339643848234588},
      {"chaotic_pile(17, 5)", piles::chaotic_pile(17, 5), 17, 0xb011ca6b1e376205ull, 0.52413730240272627},
      {"chaotic_pile(40, 399)", piles::chaotic_pile(40, 399), 40, 0x5ba6dfa535aa2be3ull, 3.6796739107412724},
      {"pile_in_view(60, 1000)", piles::pile_in_view(60, 1000), 60, 0xe94bcabacafd65e8ull, 1.325871004732498},
      {"pile_in_view(200, 1003)", piles::pile_in_view(200, 1003), 200, 0x46236fc401f328b2ull, 4.8343960498409073},
      {"figure15_both()", piles::figure15_both(), 3, 0x1e0c0044383e2e56ull, 0.20000000000000001},
      {"wall_pile(3, 2, 7)", piles::wall_pile(3, 2, 7), 6, 0x7e56b5a1705c61caull, -2.0988531612317454},
      {"wall_pile(12, 5, 42, 0.3)", piles::wall_pile(12, 5, 42, 0.3), 60, 0xb947469cc83c8f42ull, -5.2690275579741455},
      {"toppling_pile(12, 5, 4, 1.33, 17)", piles::toppling_pile(12, 5, 4, 1.33, 17), 60, 0xed7284a59e6b0782ull, -4.3149243857149431},
      {"stairs_pile(6, 10, 0.44, 23)", piles::stairs_pile(6, 10, 0.44, 23), 60, 0x28bdfb70629e12ebull, -7.9564706771320086},
      {"tower_pile(60, 33, 0.6, 9)", piles::tower_pile(60, 33, 0.6, 9), 60, 0x8a0e8ec7f6ceae80ull, -0.27077916603602326},
  };
  for (const Pinned& p : pinned) {
    INFO(p.name);
    REQUIRE(p.pile.blocks.size() == p.blocks);
    CHECK(p.pile.blocks.back().x == p.last_x);
    CHECK(digest(p.pile) == p.digest);
  }
}

TEST_CASE("the same seed gives the same pile, another seed another one") {
  CHECK(digest(piles::player_pile(30, 5)) == digest(piles::player_pile(30, 5)));
  CHECK(digest(piles::player_pile(30, 5)) != digest(piles::player_pile(30, 6)));
  CHECK(digest(piles::chaotic_pile(30, 5)) == digest(piles::chaotic_pile(30, 5)));
  CHECK(digest(piles::chaotic_pile(30, 5)) != digest(piles::chaotic_pile(30, 6)));
  CHECK(digest(piles::random_pile(5, {.blocks = 30})) == digest(piles::random_pile(5, {.blocks = 30})));
  CHECK(digest(piles::random_pile(5, {.blocks = 30})) != digest(piles::random_pile(6, {.blocks = 30})));
  CHECK(digest(piles::pile_in_view(30, 4)) == digest(piles::pile_in_view(30, 4)));
  CHECK(digest(piles::pile_in_view(30, 4)) != digest(piles::pile_in_view(30, 6)));
  CHECK_THROWS_AS(piles::random_pile(1, {.blocks = -1}), std::invalid_argument);
}

TEST_CASE("the fixtures are the optimal stacks of tests/data, each balanced on its knife edge") {
  const auto stacks = piles::fixture_stacks();
  const uint64_t digests[] = {0x67677891ee116c94ull, 0x52cc0b7623e1984dull, 0x8d30fc1cda955843ull, 0xa49a3befc2a56f63ull};
  REQUIRE(stacks.size() == 4);
  for (size_t i = 0; i < stacks.size(); ++i) {
    INFO("fixture " << i);
    CHECK(stacks[i].blocks.size() == i + 3);
    CHECK(digest(stacks[i]) == digests[i]);
    CHECK(core::predict(stacks[i]).balanced);
    CHECK_FALSE(core::predict(piles::push_rightmost(stacks[i], 1e-3)).balanced);
  }
  CHECK_THROWS_AS(piles::fixture_stacks("/nonexistent/stacks.json"), std::runtime_error);
}
