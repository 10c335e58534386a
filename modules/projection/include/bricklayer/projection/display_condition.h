// The seed paper's three display conditions and how each one lights the pile, as plain data (no SDL,
// no bus), so the big display, the miniature and the beep take their colours from one decision and
// tests drive it directly.
//
//   blue:     every block blue, always: no red, no beep, no knife-edge outline, no margin text, no ghost.
//   red:      every block blue while the pile stands, every block red while it certainly falls (the
//             pile's fate only, never which block): no knife-edge outline, no margin text, no ghost.
//             A knife edge (VERDICT_KNIFE_EDGE) does not certainly fall, so under red it is all blue.
//   proposed: only the blocks that start the collapse red (magenta: moved by them), the knife-edge
//             outline, the margin text and the collapse ghost: the exhibit's default.
// In every condition a block without a verdict yet and every block while an input is stale are dim
// blue: that says the system has no answer, not how the pile stands. Hints (only on request) are the
// planner's and are shown in every condition.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "bricklayer/projection/palette.h"
#include "bricklayer/projection/scene.h"

namespace bricklayer::projection {

// The values are study_session_t::CONDITION_* (and command_t SET_CONDITION's index, round_t.condition).
enum class DisplayCondition : int8_t { kBlue = 1, kRed = 2, kProposed = 3 };

// nullopt for anything but 1, 2, 3.
std::optional<DisplayCondition> condition_from_index(int64_t index);
// "blue", "red", "proposed"; nullopt otherwise.
std::optional<DisplayCondition> condition_from_name(const std::string& name);
const char* condition_name(DisplayCondition condition);
// The C key's order: blue -> red -> proposed -> blue.
DisplayCondition next_condition(DisplayCondition condition);

// How the pile is drawn under a condition.
struct PileLook {
  std::vector<Rgb> fill;     // one per Scene::blocks(), same order
  bool alarm = false;        // a red block is shown: the beep may sound
  bool knife_edge = false;   // draw the knife-edge outline (knife_edge_look.h) when the prediction is one
  bool margin_text = false;  // draw the margin under the miniature
  bool ghost = false;        // draw the collapse preview
};

// stale: an input is stale (the blocks lose their verdicts in every condition).
PileLook pile_look(DisplayCondition condition, const Scene& scene, bool stale);

}  // namespace bricklayer::projection
