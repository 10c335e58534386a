// The verdict a pile on its boundary shows, frame after frame: a band so that measurement noise cannot make
// it flicker between knife edge and a certain verdict (prediction README "Knife edges on the bus").
//
// A certain verdict (stable, falls) is shown as soon as it is proved, except right after a knife edge: then
// it must be proved with room to spare, |margin| >= (1 + band) x the uncertainty. The band only ever turns a
// certain verdict into a knife edge, never the other way, so what is shown is never more certain than the
// stack's own verdict. Deterministic: a function of the sequence of answers.
#pragma once

#include <cstdint>

#include "bricklayer/prediction_t.hpp"

namespace bricklayer::prediction {

// Block lengths of frame-to-frame jitter of a knife edge's margin are about twice vision's per-block noise
// (two blocks' errors add); half the uncertainty covers that at the default floor.
inline constexpr double kHysteresisBand = 0.5;

class VerdictHysteresis {
 public:
  explicit VerdictHysteresis(double band = kHysteresisBand);

  // The verdict to show for this answer (p.raw_verdict, p.margin, p.uncertainty); answers that are not
  // STATUS_OK leave the state alone and show a knife edge.
  int8_t update(const prediction_t& p);
  void reset() { shown_ = -1; }

 private:
  double band_;
  int8_t shown_ = -1;  // -1: nothing shown yet
};

}  // namespace bricklayer::prediction
