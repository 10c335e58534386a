// VerdictHysteresis: a pile on its boundary does not flicker; the shown verdict is never more certain than
// the stack's own.
#include "bricklayer/prediction/verdict_hysteresis.h"

#include <catch2/catch.hpp>

#include <vector>

using namespace bricklayer;
using prediction::VerdictHysteresis;

namespace {

constexpr double kU = 0.003;

prediction_t answer(int8_t raw, double margin) {
  prediction_t p{};
  p.status = prediction_t::STATUS_OK;
  p.raw_verdict = raw;
  p.margin = margin;
  p.uncertainty = kU;
  return p;
}

constexpr int8_t kStable = prediction_t::VERDICT_STABLE;
constexpr int8_t kFalls = prediction_t::VERDICT_FALLS;
constexpr int8_t kKnife = prediction_t::VERDICT_KNIFE_EDGE;

}  // namespace

TEST_CASE("a certain verdict right after a knife edge needs room to spare") {
  VerdictHysteresis h;
  CHECK(h.update(answer(kStable, 1.2 * kU)) == kStable);  // first answer: shown as it is
  CHECK(h.update(answer(kKnife, 0.9 * kU)) == kKnife);    // leaving stable: at once
  CHECK(h.update(answer(kStable, 1.2 * kU)) == kKnife);   // back within the band: still a knife edge
  CHECK(h.update(answer(kStable, 1.49 * kU)) == kKnife);
  CHECK(h.update(answer(kStable, 1.5 * kU)) == kStable);  // clear of the band
  CHECK(h.update(answer(kStable, 1.1 * kU)) == kStable);  // and stays while it is proved
  CHECK(h.update(answer(kFalls, -1.1 * kU)) == kFalls);   // certain to certain: no band
  CHECK(h.update(answer(kKnife, -0.5 * kU)) == kKnife);
  CHECK(h.update(answer(kFalls, -1.2 * kU)) == kKnife);
  CHECK(h.update(answer(kFalls, -1.6 * kU)) == kFalls);
}

TEST_CASE("jitter across the boundary: one change, then no flicker") {
  // A standing pile whose measured margin jitters between 0.8 u and 1.4 u (vision noise): without the band it
  // would alternate between stable and knife edge every frame.
  VerdictHysteresis h;
  std::vector<int8_t> shown;
  for (int f = 0; f < 60; ++f) {
    const double margin = (f % 2 == 0 ? 1.4 : 0.8) * kU;
    shown.push_back(h.update(answer(margin >= kU ? kStable : kKnife, margin)));
  }
  int changes = 0;
  for (size_t i = 1; i < shown.size(); ++i) changes += shown[i] != shown[i - 1];
  CHECK(changes == 1);
  CHECK(shown.back() == kKnife);
}

TEST_CASE("never more certain than the stack's own verdict, failures show a knife edge and keep the state") {
  VerdictHysteresis h;
  for (int8_t raw : {kStable, kKnife, kFalls, kKnife, kStable, kFalls, kStable}) {
    for (double m : {0.5, 1.2, 3.0}) {
      const int8_t s = h.update(answer(raw, (raw == kFalls ? -m : m) * kU));
      CHECK((s == raw || s == kKnife));
    }
  }
  VerdictHysteresis g;
  CHECK(g.update(answer(kKnife, 0.0)) == kKnife);
  prediction_t bad = answer(kStable, 0.05);
  bad.status = prediction_t::STATUS_INVALID_STACK;
  CHECK(g.update(bad) == kKnife);
  CHECK(g.update(answer(kStable, 1.2 * kU)) == kKnife);  // the knife edge before the failure still holds
  CHECK_THROWS_AS(VerdictHysteresis(-1.0), std::invalid_argument);
}
