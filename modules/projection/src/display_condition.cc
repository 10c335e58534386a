#include "bricklayer/projection/display_condition.h"

#include <algorithm>

namespace bricklayer::projection {

std::optional<DisplayCondition> condition_from_index(int64_t index) {
  switch (index) {
    case 1: return DisplayCondition::kBlue;
    case 2: return DisplayCondition::kRed;
    case 3: return DisplayCondition::kProposed;
    default: return std::nullopt;
  }
}

std::optional<DisplayCondition> condition_from_name(const std::string& name) {
  if (name == "blue") return DisplayCondition::kBlue;
  if (name == "red") return DisplayCondition::kRed;
  if (name == "proposed") return DisplayCondition::kProposed;
  return std::nullopt;
}

const char* condition_name(DisplayCondition condition) {
  switch (condition) {
    case DisplayCondition::kBlue: return "blue";
    case DisplayCondition::kRed: return "red";
    case DisplayCondition::kProposed: break;
  }
  return "proposed";
}

DisplayCondition next_condition(DisplayCondition condition) {
  switch (condition) {
    case DisplayCondition::kBlue: return DisplayCondition::kRed;
    case DisplayCondition::kRed: return DisplayCondition::kProposed;
    case DisplayCondition::kProposed: break;
  }
  return DisplayCondition::kBlue;
}

PileLook pile_look(DisplayCondition condition, const Scene& scene, bool stale) {
  PileLook look;
  const auto& blocks = scene.blocks();
  look.fill.reserve(blocks.size());
  if (stale) {
    look.fill.assign(blocks.size(), kUnknownDimBlue);
    return look;
  }
  // A cause is drawn only for a pile that certainly falls (prediction README): the one signal of a fall
  // that every condition reads the same way, older-frame colours included (scene.h).
  const bool falls = scene.any_cause();
  for (const SceneBlock& b : blocks) {
    switch (condition) {
      case DisplayCondition::kBlue:
        look.fill.push_back(b.state == BlockState::kUnknown ? kUnknownDimBlue : kStableBlue);
        break;
      case DisplayCondition::kRed:
        // Every block while it falls, the ones without a verdict yet included: the pile's fate, not a block's.
        look.fill.push_back(falls ? kCauseRed : b.state == BlockState::kUnknown ? kUnknownDimBlue : kStableBlue);
        break;
      case DisplayCondition::kProposed: look.fill.push_back(colour_for(b.state)); break;
    }
  }
  look.alarm = falls && condition != DisplayCondition::kBlue;
  const bool details = condition == DisplayCondition::kProposed;
  look.knife_edge = details;
  look.margin_text = details;
  look.ghost = details;
  return look;
}

}  // namespace bricklayer::projection
