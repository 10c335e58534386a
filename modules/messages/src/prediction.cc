#include "bricklayer/messages/prediction.h"

#include "bricklayer/block_prediction_t.hpp"

namespace bricklayer::messages {

void put_verdict(const core::Prediction& verdict, prediction_t& out) {
  out.balanced = verdict.balanced;
  out.overhang = verdict.overhang;
  out.score = verdict.score;
  if (!verdict.annotator.empty()) out.annotator = verdict.annotator;
  if (!verdict.solver.empty()) out.solver = verdict.solver;
  out.blocks.clear();
  out.blocks.reserve(verdict.blocks.size());
  for (const auto& v : verdict.blocks) {
    block_prediction_t b{};
    b.id = v.id;
    b.state = static_cast<int8_t>(v.state);
    b.accel = v.accel;
    b.alpha = v.alpha;
    b.deciding = false;
    b.uncertainty = 0.0;
    out.blocks.push_back(b);
  }
  out.num_blocks = static_cast<int32_t>(out.blocks.size());
}

}  // namespace bricklayer::messages
