// How a pile on its knife edge looks (prediction_t.verdict == VERDICT_KNIFE_EDGE), as plain data: the
// deciding blocks keep their blue fill and get a red outline that pulses slowly (no green light needed, and
// not the steady red of a certain fall, which alone beeps); the margin as text for every judged pile.
// Pure (no SDL), so tests drive it directly; GameRenderer draws it on the board and in the miniature.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "bricklayer/prediction_t.hpp"
#include "bricklayer/projection/palette.h"

namespace bricklayer::projection {

// One slow pulse of the outline, milliseconds: slow enough not to read as an alarm.
inline constexpr int64_t kKnifeEdgePulseMs = 1600;

struct KnifeEdgeLook {
  bool knife_edge = false;       // the pile is shown as a knife edge
  std::vector<int64_t> outlined;  // ids of the blocks to outline (blocks[].deciding)
  Rgb outline{};                 // the outline's colour now: red, pulsing between 40 % and 100 %
  std::string margin_text;       // "2.0 mm to spare", "0.3 mm too far", "on the edge"; "" when not judged
};

// The look for the prediction that answers the drawn stack (nullptr: none), at animation time anim_ms.
// A prediction judged without uncertainty (uncertainty 0: older recordings, the legacy widening) gets no
// margin text.
KnifeEdgeLook knife_edge_look(const prediction_t* prediction, int64_t anim_ms);

// "2.0 mm to spare" (margin > 0), "0.3 mm too far" (< 0), "on the edge" (|margin| < 0.05 mm); at the cap
// (3.75 mm) "more than 3.7 mm to spare" / "more than 3.7 mm too far".
std::string margin_text(double margin_mm);

}  // namespace bricklayer::projection
