// A simcam scenario: what a scripted player does in front of the camera, as a timeline of stacks.
//
// File format (JSON; every key checked, unknown keys are errors so a typo never passes silently):
//   {"description": "...",            text for the operator
//    "nuisance": "mild",              clean | mild | strong | harsh (simcam::Nuisance::named)
//    "seed": 7,                       noise and shadow layout seed (frames use seed + frame number)
//    "duration_s": 24,                optional; default: last key frame + 5 s
//    "block_height": 0.3333,          optional; block height in block lengths (default 1/3)
//    "keyframes": [{"t": 0.0, "blocks": [{"id": 1, "row": 0, "x": -0.5}, ...]}, ...]}
// The stack shown at time t is the last key frame with key.t <= t (a player places blocks one at a
// time; there is no interpolation). Key frames must be in increasing time order; blocks are validated
// like bricklayer-predict's input, except that a block resting on nothing is allowed (it is falling).
#pragma once

#include <string>
#include <vector>

#include "bricklayer/core/stack.h"
#include "bricklayer/simcam/render.h"

namespace bricklayer::simcam {

struct KeyFrame {
  double t = 0.0;  // seconds from the scenario's start
  core::Stack stack;
};

struct Scenario {
  std::string description;
  Nuisance nuisance;
  uint64_t seed = 1;
  double duration_s = 0.0;
  std::vector<KeyFrame> keyframes;

  // The stack at time t (seconds; looped scenarios pass t modulo duration_s).
  const core::Stack& stack_at(double t) const;
};

// Throws std::runtime_error with a message naming the file, the key frame and the problem.
Scenario parse_scenario(const std::string& json_text, const std::string& name = "scenario");
Scenario load_scenario(const std::string& path);

}  // namespace bricklayer::simcam
