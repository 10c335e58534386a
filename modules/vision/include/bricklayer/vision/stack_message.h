// Detections out: as stack_t on BL_STACK, or as a line of bricklayer-predict's JSON input (the offline
// --images DIR --json mode).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "bricklayer/detection/board_frame.h"
#include "bricklayer/detection/detector.h"
#include "bricklayer/stack_t.hpp"
#include "bricklayer/vision/temporal_filter.h"

namespace bricklayer::vision {

// Block height in block lengths of a board frame.
double block_height_blocks(const detection::BoardFrame& frame);

// A stack message from a detection (ids 0.. left to right, bottom row first) or from filtered blocks.
// `x_uncertainty`: each block's published half-width (position_uncertainty.h), one per block in the same
// order, or empty for none (0: prediction then uses its floor). Throws std::invalid_argument for another count.
stack_t to_stack_message(const detection::Detection& detection, const detection::BoardFrame& frame, int64_t utime,
                         int64_t frame_number, const std::vector<double>& x_uncertainty = {});
stack_t to_stack_message(const std::vector<FilteredBlock>& blocks, const detection::BoardFrame& frame, int64_t utime,
                         int64_t frame_number, const std::vector<double>& x_uncertainty = {});
stack_t no_frame_stack(const detection::BoardFrame& frame, int64_t utime, int64_t frame_number);

// One line of bricklayer-predict's input:
// {"block_length":1,"block_height":h,"table_edge":0,"blocks":[{"id":0,"row":0,"x":-0.5},...]}.
std::string to_predict_json(const detection::Detection& detection, const detection::BoardFrame& frame);

}  // namespace bricklayer::vision
