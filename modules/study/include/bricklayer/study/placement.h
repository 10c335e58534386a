// The fewest blocks that make a given pile stand: a search over placements of added blocks, every
// placement judged by the exact annotator, with a proof that fewer blocks cannot do it.
//
// Coordinates are block lengths with the surface edge at x = 0 (core's normalised units). An added block
// goes into any row at any x where it overlaps no block of its row (touching is allowed) and rests on
// something: a block that rests on nothing is a cause by definition, and a row-0 block that carries
// nothing changes no other block's equilibrium, so neither can help.
//
// One added block: exact (up to the balance tolerance). As the block slides along its row, the contact
// geometry changes only at critical positions (where one of its ends meets an end of a block in the row
// below or above, or the surface edge); between two of them every contact end is either fixed or moves
// with the block. The least equilibrium violation V(x) (the balance LP's objective, with the total force
// on the added block's contacts bounded by 2n, which no balanced pile of n blocks exceeds) is then
// Lipschitz in x with constant 2n: each contact force changes exactly one moment arm, at rate 1. So V at
// two points of a cell bounds V between them from below, and the search subdivides a cell until either
// every piece is proven unbalanced (V > kBalanceTolerance) or a placement is found that the exact
// annotator calls balanced. A piece narrower than min_interval that is neither is "undecided" and makes
// the result inexact (reported, never hidden).
//
// Two or more added blocks: a search for a witness only, over every row and a grid (pair_step) inside
// each cell of the critical positions, the second block's candidates computed on the pile with the first
// (so it may rest on it or carry it; a block that only carries something, to be propped by a later one,
// is a candidate too). It proves nothing when it finds nothing; the minimum is then
// reported as not found up to max_added.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "bricklayer/core/stack.h"

namespace bricklayer::study {

struct Placement {
  int32_t row = 0;
  double x = 0.0;  // left end, block lengths from the surface edge
};

// A closed range of x for an added block's left end; lo == hi is a single position (a gap exactly one
// block wide).
struct Range {
  double lo = 0.0;
  double hi = 0.0;
};

struct SearchOptions {
  double position_tolerance = 0.005;  // judgement of the exact annotator (core PredictOptions), block lengths
  int max_added = 2;                  // search up to this many added blocks
  double min_interval = 1e-6;         // one-block proof: pieces narrower than this are undecided
  double pair_step = 0.02;            // two-block witness grid, block lengths
  size_t max_evaluations = 3'000'000; // bound on exact-annotator calls of the witness search
};

struct MinimumResult {
  int minimum = -1;  // fewest added blocks that make the pile stand; -1: none found up to max_added
  // True when every smaller count is proven impossible (0 by the annotator, 1 by the certified search).
  // A minimum of 3 or more, or none found, is never proven.
  bool proven = false;
  std::vector<Placement> witness;  // a placement of `minimum` blocks that stands
  size_t lp_evaluations = 0;       // bounded-violation LPs solved by the one-block proof
  size_t predictions = 0;          // exact-annotator calls
  size_t undecided = 0;            // one-block pieces neither proven nor solved
  std::string summary;             // one line, e.g. "2 (proven: 0 and 1 impossible, 1843 LPs)"
};

// The pile with the added blocks appended (ids after the largest id of the pile).
core::Stack with_added(const core::Stack& pile, const std::vector<Placement>& added);

// Whether the exact annotator calls the pile balanced with the given position tolerance.
bool stands(const core::Stack& pile, double position_tolerance);

// Where one block may be added in `row` (see the file comment), in increasing order. `pile` is normalised.
// With `or_carrying`, a block of row >= 1 may also rest on nothing yet but carry a block of the row above
// (a prop that a further added block will support).
std::vector<Range> placement_ranges(const core::Stack& pile, int32_t row, bool or_carrying = false);

// The positions in [lo, hi] where the added block's contact geometry in `row` changes, sorted, with lo and
// hi included.
std::vector<double> critical_positions(const core::Stack& pile, int32_t row, const Range& range);

// V(x) of the file comment for the pile with one block added at `added` (block `added_index` of the
// returned with_added stack), judged with the given position tolerance.
double bounded_violation(const core::Stack& pile, const Placement& added, double position_tolerance);

// The rows an added block can go into: 0 .. (highest row of the pile) + 1.
int32_t highest_useful_row(const core::Stack& pile);

// The fewest added blocks (0 .. options.max_added). `pile` must be normalised (block_length 1, edge 0);
// throws core::StackError when it is not valid.
MinimumResult minimum_added(const core::Stack& pile, const SearchOptions& options = {});

// The same pile in normalised units: block_length 1, surface edge at x = 0 (block_height scaled too).
core::Stack normalised(const core::Stack& pile);

// Brute force, for tests: every placement of `count` blocks on a uniform grid of `step` (block lengths)
// in every row from 0 to one above the top, x from one length left of the leftmost block to one length
// right of the rightmost (anything farther touches nothing), each judged by the exact annotator; returns
// the first that stands (empty when none does). Deliberately independent of the certified search: no
// ranges, no critical positions, no LP.
std::vector<Placement> brute_force_witness(const core::Stack& pile, int count, double step,
                                           double position_tolerance, size_t* evaluations = nullptr);

}  // namespace bricklayer::study
