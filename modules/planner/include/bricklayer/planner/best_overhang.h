// Best possible overhang of n identical blocks (Paterson & Zwick's model, shared DESIGN.md "The physics").
//
// A layout fixes each block's row; positions and contact forces are the unknowns. Every pair of blocks in
// adjacent rows (and every row-0 block with the surface) gets a resultant force f >= 0 and its moment
// m = f * p about x = 0; the point of application p must lie in the contact interval [max left ends,
// min right ends], i.e. f*lo <= m <= f*hi. That is exactly "nonnegative forces at the two ends of the
// interval" and forces f = 0 on pairs that do not overlap. Equilibrium of every block is linear in (x, f, m);
// the interval constraints are bilinear. A sequential-linear-programming trust-region method (CLP for the
// linear programs) maximises the target block's right end; every answer's constraint residual is measured.
// The search grows layouts block by block (beam search over where the next block goes) with seeded
// perturbations, brick-wall starts and optional one-block moves: deterministic for a given seed.
#pragma once

#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

namespace bricklayer::planner {

struct PlacedBlock {
  int row = 0;
  double x = 0.0;  // left end, block lengths; surface occupies x <= 0
};

struct OverhangStack {
  double overhang = 0.0;  // rightmost right end, block lengths
  double residual = 0.0;  // largest constraint violation of the optimiser's answer
  std::vector<PlacedBlock> blocks;  // sorted by row, then x
};

// What one optimisation cost (for benchmarks and the generator's progress figures).
struct OptimiseStats {
  int iterations = 0;        // trust-region steps
  int linear_programs = 0;   // linear programs solved
  int failed_programs = 0;   // of those, ended without an optimal answer (the step is then shrunk)
};

// Optimises the positions of a layout (rows fixed, x the start) for the largest overhang of block target.
// Returns nothing when the optimiser ends infeasible (residual above tolerance), which is common for starts
// far from balanced. Throws std::invalid_argument on a target out of range, a negative row, a non-finite x or
// a row with no row below it. stats (optional) receives what the optimisation cost.
std::optional<OverhangStack> optimise_layout(const std::vector<PlacedBlock>& start, int target,
                                             double tolerance = 1e-9, OptimiseStats* stats = nullptr);

// Seeded brick-wall start layouts of n blocks with random row profiles (used by the search for n >= 8).
std::vector<std::vector<PlacedBlock>> wall_layouts(int n, int count, uint64_t seed);

// The best stack of one block less that s leaves: each block whose removal keeps a row under every other
// row is taken away in turn and the rest re-optimised from their positions (nothing when none converges).
// The beam grows layouts only upwards in n, and the best n-1 stack is sometimes the best n one minus a block.
// jobs: optimisations run at once (the answer is the same for any value).
std::optional<OverhangStack> best_one_block_less(const OverhangStack& s, double tolerance = 1e-9, int jobs = 1);

// Whether the exact annotator (core::predict, zero position tolerance) calls stack s balanced. The search writes
// a row only when it does: the optimiser's own check is its linear program (residual <= tolerance), and the
// annotator's QP (NNLS on normal equations) can read a stack whose contacts overlap by the 1e-4 minimum as
// moving at a few 1e-6 g (a 51-block stack of 3.310260: the LP residual 1e-14, the NLopt QP and the LP-first
// check call it balanced, the default NNLS does not). The table promises stacks the display calls blue.
bool annotator_balanced(const OverhangStack& s);

// Where a search stands after an n: everything the next n depends on, so that a run stopped after any n and
// continued from this state writes byte for byte the files of a run that was never stopped.
struct OverhangSearchState {
  int first_new = 2;                      // the first n the run computed (shrink never changes rows below it)
  std::vector<OverhangStack> best_per_n;  // index n-1, n = 1..the last n finished
  std::vector<OverhangStack> beam;        // the layouts the next n grows from
  std::string rng;                        // the random engine's state (std::mt19937_64 as operator<< writes it)
};

struct OverhangSearchOptions {
  int beam = 8;           // layouts kept per n
  // Of layouts reaching the same overhang (to 1e-9), at most this many go into the beam and the restarts
  // (0: no limit). Without it the beam held one stack eight times over: the same blocks below the load, the
  // counterweights on top arranged differently (1,1,1 or 2,1 or 3 blocks), every copy the same overhang.
  int alike = 1;
  // From n = variety_from on, up to this many more layouts join the beam: the best of each row of the
  // rightmost block (the load point) that the beam does not have yet. Without them every layout in the beam
  // had its load on one row (row 9 at n = 40), and stacks with their load higher, which start behind and
  // overtake from about n = 42, were dropped (the search fell behind the table from n = 45). From 41: below,
  // the narrower beam already reaches the published optima, and each of these layouts costs time at every n.
  int variety = 4;
  int variety_from = 41;
  int perturbations = 4;  // seeded random restarts around the best layouts per n
  int wall_seeds = 6;     // seeded brick-wall layouts with random row profiles per n (n >= 8)
  // After each n: the best n stack minus one block (each block tried, re-optimised) replaces the best n-1 one
  // when better, and so on down (rows of resume_from are never changed).
  bool shrink = true;
  int moves = 0;           // local improvement: re-optimisations of one-block moves tried per n (n >= 4)
  uint64_t seed = 1;
  double tolerance = 1e-9;  // largest accepted constraint residual
  // Optimisations run at once, on threads. The answer does not depend on it: the random draws happen on the
  // calling thread and the answers are taken in the order of their start layouts.
  int jobs = 1;
  // Results already known for n = 1..k (e.g. from an earlier run's stacks file): the search continues at
  // n = k+1 with the last of them as its only layout.
  std::vector<OverhangStack> resume_from;
  // Extra start layouts, index n-1 (e.g. an earlier run's stacks file): each is re-optimised at its n as one
  // more candidate, so a run never ends below the layouts it was given (path-dependent beam searches differ).
  std::vector<OverhangStack> start_layouts;
  // A state an earlier run reported (its checkpoint): the search goes on from there exactly as that run would
  // have, given the same options. Excludes resume_from. Throws std::invalid_argument on a state that does not
  // hold together (rows of the wrong size, an unreadable engine state).
  std::optional<OverhangSearchState> continue_from;
};

// Best stacks for n = 1..n_max (index n-1). progress(n, best) is called after each n when given (again for a
// row that shrink improved); checkpoint(state) after each n is finished, when given.
std::vector<OverhangStack> search_best_overhang(int n_max, const OverhangSearchOptions& options = {},
                                                const std::function<void(int, const OverhangStack&)>& progress = {},
                                                const std::function<void(const OverhangSearchState&)>& checkpoint = {});


}  // namespace bricklayer::planner
