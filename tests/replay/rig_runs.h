// Recorded runs of the display and the calibration for the replay tests, made on the in-process rig
// from the real nodes (projection with SDL's offscreen driver, calibrate, simcam, vision, prediction,
// planner): every message the bus carried written to a standard LCM log with its publication time, as
// the logger would. The rig's clock moves in steps of 1 ms (2 ms for the calibration loop) and every
// node ticks on every step, as a live loop ticks on its refresh.
#pragma once

#include <cstdint>
#include <string>

namespace bricklayer::test {

// Piles on a board seen empty first (so a round starts by itself), fed to the real prediction,
// planner and projection nodes (320x240 projector, 3-s rounds, --state-hz 15, a status JPEG every
// second) for `seconds`; a START_ROUND and a SET_CONDITION red come from the operator on the way.
// Returns the number of events written.
int64_t record_projection_run(const std::string& path, double seconds = 8);

// A calibration run (simcam's random setup 4 on an empty board, the real projection showing the
// patterns, CalibrateNode computing) to its finish; output: where the node writes its file.
int64_t record_calibration_run(const std::string& path, const std::string& output);

// CalibrateNode --serve (republishing every second) loading calibration_file, on an empty board (the
// test's stacks), with the real simcam and projection: a SELF_CHECK command at 1.5 s is answered with
// the self-check markers; `seconds` of it.
int64_t record_serve_run(const std::string& path, const std::string& calibration_file, double seconds = 5);

// The regression log kept with the tests: `build-4-optimum` seen by the real simcam (5 frames a
// second, JPEG quality 40, the projector's light in the frames), vision, prediction, planner and
// projection (320x240, its state five times a second, rounds starting 1 s after the first block) for
// `seconds` (small: about 70 kB a second). 9 s: the first block, the pile growing, a round started,
// the right block red until the counterweight is on it (previews).
int64_t record_regression_run(const std::string& path, double seconds = 9);

}  // namespace bricklayer::test
