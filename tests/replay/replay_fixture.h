// Recorded runs for the replay tests: the real prediction and planner nodes on the in-process rig (a
// bus implementation other than the replay's), every message the bus carried written to a standard
// LCM log with its arrival time, as the logger would.
#pragma once

#include <string>
#include <vector>

#include "bricklayer/prediction/prediction_logic.h"
#include "bricklayer/stack_t.hpp"

namespace bricklayer::test {

struct RunOptions {
  prediction::PredictionConfig prediction;
  bool planner = true;
  int hint_every = 30;        // a REQUEST_HINT command after every this many stacks (0 = none)
  int64_t frame_us = 33'333;  // between stacks
};

// Writes the run to path; returns the number of events written.
int64_t record_run(const std::string& path, const std::vector<stack_t>& stacks, const RunOptions& options = {});

// A camera run: the real simcam, vision and prediction nodes on the rig, a scenario's first `frames`
// frames at 30 frames a second, every message written to path (as the logger would, frames included).
// Returns the number of events written.
int64_t record_camera_run(const std::string& path, const std::string& scenario, int frames);

// n stacks that grow, lean out and fall (some unbalanced), from prediction's sample piles.
std::vector<stack_t> demo_stacks(int n, int64_t start_utime = 1'767'225'600'000'000);

// The seed paper's Figure 15 cases (three blocks in a column), each as a stack of its own.
std::vector<stack_t> figure15_stacks(int64_t start_utime = 1'767'225'600'000'000);

}  // namespace bricklayer::test
