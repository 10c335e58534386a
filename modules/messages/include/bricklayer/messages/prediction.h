// core::Prediction -> prediction_t.
#pragma once

#include "bricklayer/core/predict.h"
#include "bricklayer/prediction_t.hpp"

namespace bricklayer::messages {

// Puts the verdict into out: balanced, overhang, score, the annotator and solver it names (when it
// names them) and one block_prediction_t per block. Leaves utime, frame_number, status, error and the
// judged-with fields to the caller.
void put_verdict(const core::Prediction& verdict, prediction_t& out);

}  // namespace bricklayer::messages
