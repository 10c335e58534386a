// Collapse preview: how the pile will fall, in the frictionless model of shared DESIGN.md "The physics".
//
// Rigid 2D blocks (length 1, height h, unit mass, I = (1 + h^2)/12, g = 1 in block lengths and the time unit
// sqrt(block length / g)). Semi-implicit Euler, steps of dt, doubled while every awake block is slow; each step
// finds the current contacts (box-box manifolds, Box2D style: reference face of least penetration, incident edge
// clipped to it, so a block on a block touches at the two ends of the contact interval; the surface is a static
// box x <= edge, y <= 0) and solves the frictionless velocity problem (normal impulses >= 0, non-penetration
// with a small Baumgarte bias) by projected Gauss-Seidel, warm-started from the previous step's impulses.
//
// Blocks the prediction calls stable start asleep (static) and wake when something they rest on moves or
// when a moving block strikes them, so the balanced part stays exactly where it is unless debris hits it.
// Awake blocks that touch one another form islands; an island whose blocks have all been awake for at least one
// time unit (a block just past its balance point starts to tip very slowly) and still for `rest_time` falls
// asleep (at rest). A block leaves the pile, and stops costing contact work, in two ways:
//   - it falls past the surface edge (its highest point below the surface): from then on it falls freely;
//   - it slides alone on the surface (lying flat on the surface itself, touching no block of the pile, clear
//     of every other block; a group of such blocks touching only one another counts too): it stops
//     where it is. The frictionless model would let it slide forever; a real table's friction stops it.
//     It stays an obstacle (asleep), so debris still lands on it and wakes it.
// The simulation ends when no block in the pile is awake (every block at rest or gone) and the blocks that
// fell have dropped `fall_depth` below the surface (for the animation), or at max_time.
// Deterministic: the same input and options give bit-identical output.
#pragma once

#include <cstdint>
#include <vector>

namespace bricklayer::planner {

struct Pose {
  double x = 0.0;      // centre, block lengths
  double y = 0.0;      // centre, block lengths above the surface
  double angle = 0.0;  // radians, counter-clockwise
};

struct CollapseInput {
  double block_height = 1.0 / 3.0;  // block lengths
  double table_edge = 0.0;          // block lengths
  struct Block {
    int row = 0;
    double x = 0.0;       // left end, block lengths
    bool moving = true;   // false: starts asleep (the prediction says it stays at rest): see starts_awake
  };
  std::vector<Block> blocks;
};

// Whether a block starts the preview awake (CollapseInput::Block::moving), from the prediction's verdict and
// initial accelerations (units of g; 0 from annotators that give none): every block not called stable, and a
// block called stable whose acceleration is not zero but below the annotator's tolerance (1e-6). Frozen, such a
// block can hold up a knife-edge pile the annotator lets fall: a 55-block best stack of the table's search with
// its rightmost block pushed out by 1e-4 has a row-1 block at 9.7e-7, and with it asleep nothing moved at all in
// the first step while 53 blocks accelerate in the annotator's QP. Accelerations of at most 1e-9 (a balance
// certificate's exact zero, the QP's rounding at 1e-14) count as zero: those blocks start asleep.
bool starts_awake(bool stable, double accel, double alpha);

struct CollapseOptions {
  double dt = 0.01;                  // time step, time units
  double max_time = 8.0;             // time units
  double key_frame_interval = 0.2;   // time units between key frames (the first is t = 0)
  int max_iterations = 8;            // Gauss-Seidel sweeps per island and step at most
  double tolerance = 1e-4;           // sweeps stop early when no impulse changes by more than this
  double rest_speed = 0.01;          // block lengths per time unit: still = vertical speed and spin (at the ends) below
  // Sideways drift that still counts as rest for a block that is otherwise still (no vertical speed, no spin).
  // Frictionless, a block that came down flat keeps whatever sideways speed the contacts gave it, for ever;
  // real blocks have friction and stop. 0.1 block lengths per time unit = 8.6 cm/s for 7.5 cm blocks.
  double rest_slide_speed = 0.1;
  double rest_time = 0.3;            // time units an island must stay still to fall asleep
  double fall_depth = 1.0;           // block lengths below the surface a falling block is followed
};

// How each block ends.
enum class BlockEnd : int8_t {
  kUntouched = 0,  // asleep from start to end: not a hair moved
  kAtRest = 1,     // moved, then came to rest in the pile (on blocks or against them)
  kSlidAway = 2,   // left the pile alone on the surface; stopped there (see the file comment)
  kFellOff = 3,    // left the pile past the surface edge
  kMoving = 4,     // still moving at max_time
};

// A rate of change of a block's velocity: x, y in block lengths per time unit^2 (units of g), angle in radians
// per time unit^2 (g per block length), counter-clockwise.
struct Acceleration {
  double x = 0.0;
  double y = 0.0;
  double angle = 0.0;
};

struct CollapsePreview {
  // The simulation's initial accelerations: each block's velocity after the first time step (released from rest)
  // divided by that step's length; zero for a block asleep through it. The same quantities as the exact
  // annotator's core::BlockVerdict::accel (y) and alpha (angle), which has no horizontal motion (x): the first
  // step's contact problem is that annotator's QP, solved approximately (README "First step").
  std::vector<Acceleration> initial;
  std::vector<double> times;                // time units, one per key frame; the last is the end
  std::vector<std::vector<Pose>> frames;    // frames[k][i]: pose of block i at times[k]
  std::vector<BlockEnd> end;                // per block
  std::vector<bool> left_pile;              // per block: kSlidAway or kFellOff
  bool came_to_rest = false;                // ended before max_time: every block at rest or gone
  int steps = 0;                            // time steps taken (double steps count once)
};

// Seconds per time unit for real blocks (7.5 cm long, g = 9.81 m/s^2).
double seconds_per_time_unit(double block_length_m = 0.075);

// Throws std::invalid_argument for a non-positive or non-finite block height, option or time, a negative
// row or a non-finite x.
CollapsePreview simulate_collapse(const CollapseInput& input, const CollapseOptions& options = {});

}  // namespace bricklayer::planner
