// Scripted study subjects: what a subject does in front of the board during a whole session, written
// as a simcam scenario (launch/scenarios format: a timeline of stacks), so a simulated study runs the
// real session driver on scripted behaviour and its report can be checked against the scripts.
//
// The timeline follows the protocol's rules (session.h): before every step the board is cleared for
// 1.5 s (the driver runs a step after clear_ms of empty board), a game's pile stands until the game is
// over, a correct or excess answer stands until the driver has taken it (settle_ms), a failed one
// until the problem's time is up.
#pragma once

#include <array>
#include <cstdint>
#include <string>

#include "bricklayer/core/stack.h"
#include "bricklayer/study/checker.h"
#include "bricklayer/study/problem.h"
#include "bricklayer/study/session.h"

namespace bricklayer::study {

struct SubjectScript {
  int32_t trial1_score = 50;  // 1..117: the standing pile the subject builds in the first game
  int32_t trial2_score = 60;
  std::array<Outcome, 3> answers{Outcome::kCorrect, Outcome::kCorrect, Outcome::kCorrect};  // excess only for 1, 2
  std::string description;
};

// A standing pile of four blocks whose score is exactly `score` (1..117): the harmonic stack (104) or the
// four-block optimum (117) moved left. Throws std::invalid_argument outside 1..117.
core::Stack pile_with_score(int32_t score);

// The scenario JSON (simcam's format) of one scripted session. Throws std::invalid_argument for an
// outcome a problem cannot have (excess on the score problem).
std::string subject_scenario_json(const SubjectScript& script, const SessionSetup& timing, const Problem& problem1,
                                  const Problem& problem2, const Problem& problem3, uint64_t seed = 1);

}  // namespace bricklayer::study
