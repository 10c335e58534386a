// Collapse preview: how the pile will fall, in the frictionless model of shared DESIGN.md "The physics".
//
// Rigid 2D blocks (length 1, height h, unit mass, I = (1 + h^2)/12, g = 1 in block lengths and the time unit
// sqrt(block length / g)). Semi-implicit Euler with small steps; each step finds the current contacts
// (box-box manifolds, Box2D style: reference face of least penetration, incident edge clipped to it, so a
// block on a block touches at the two ends of the contact interval; the surface is a static box x <= edge,
// y <= 0) and solves the frictionless velocity problem (normal impulses >= 0, non-penetration with a small
// Baumgarte bias) by projected Gauss-Seidel. Blocks the prediction calls stable start asleep (static) and
// wake when something they rest on moves or when a moving block strikes them, so the balanced part stays
// exactly where it is unless debris hits it. A block whose centre falls below the surface level beyond the
// edge has left the pile: it keeps falling freely without contacts. The simulation stops when every awake
// block has left or is at rest, or at max_time.
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
    bool moving = true;   // false: starts asleep (the prediction says it stays at rest)
  };
  std::vector<Block> blocks;
};

struct CollapseOptions {
  double dt = 0.01;                  // time step, time units
  double max_time = 8.0;             // time units
  double key_frame_interval = 0.2;   // time units between key frames (the first is t = 0)
  int iterations = 12;               // Gauss-Seidel sweeps per step
  double left_depth = 0.5;           // a block has left the pile when its centre is this far below the surface
};

struct CollapsePreview {
  std::vector<double> times;                // time units, one per key frame
  std::vector<std::vector<Pose>> frames;    // frames[k][i]: pose of block i at times[k]
  std::vector<bool> left_pile;              // per block, at the end
  bool came_to_rest = false;                // every block still in the pile is at rest at the end (false: max_time)
  int steps = 0;
};

// Seconds per time unit for real blocks (7.5 cm long, g = 9.81 m/s^2).
double seconds_per_time_unit(double block_length_m = 0.075);

CollapsePreview simulate_collapse(const CollapseInput& input, const CollapseOptions& options = {});

}  // namespace bricklayer::planner
