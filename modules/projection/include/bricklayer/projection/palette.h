// The colours of the game display. Only the red and blue channels are ever lit: the camera measures
// the blocks' dark end lines in the green channel, so green stays 0 in every pixel we draw (patterns
// for calibration are the one exception, and they are not the game display).
#pragma once

#include <cstdint>

namespace bricklayer::projection {

struct Rgb {
  uint8_t r = 0;
  uint8_t b = 0;
  // No green member on purpose: a game colour cannot carry green.
};

// Block states as drawn. kUnknown: no prediction has been seen for this block yet.
enum class BlockState : int8_t { kUnknown = -1, kStable = 0, kMoving = 1, kCause = 2 };

inline constexpr Rgb kStableBlue{0, 255};
inline constexpr Rgb kCauseRed{255, 0};
inline constexpr Rgb kMovingMagenta{255, 255};  // moves, but only because what it rests on moves
inline constexpr Rgb kUnknownDimBlue{0, 90};
inline constexpr Rgb kText{200, 255};           // score, MAX, timer: a bright violet
inline constexpr Rgb kTextWarning{255, 60};     // the last seconds of a round
inline constexpr Rgb kTextDim{110, 160};        // secondary lines
inline constexpr Rgb kSurface{60, 140};         // the surface in the miniature
inline constexpr Rgb kGhost{120, 120};          // collapse preview outlines
inline constexpr Rgb kHint{0, 255};             // hint outlines
// A study problem's pile to build (problem_outline.h): a dull violet, unlike the verdicts' blue, red and
// magenta and dimmer than them, so a subject never reads an outline as a verdict.
inline constexpr Rgb kProblemOutline{170, 120};

inline constexpr Rgb colour_for(BlockState state) {
  switch (state) {
    case BlockState::kStable: return kStableBlue;
    case BlockState::kMoving: return kMovingMagenta;
    case BlockState::kCause: return kCauseRed;
    case BlockState::kUnknown: break;
  }
  return kUnknownDimBlue;
}

}  // namespace bricklayer::projection
