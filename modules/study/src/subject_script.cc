#include "bricklayer/study/subject_script.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <vector>

#include <nlohmann/json.hpp>

namespace bricklayer::study {
namespace {

// Known four-block optimum, overhang 1.16789 (modules/planner/data/best_overhang.json).
const core::Stack& optimum_four() {
  static const core::Stack s = [] {
    core::Stack p;
    p.blocks = {{1, 0, -0.47855339}, {2, 1, -1.15621109}, {3, 1, 0.16789322}, {4, 2, -0.53312874}};
    return p;
  }();
  return s;
}

core::Stack harmonic_four() {
  core::Stack s;
  // Block k from the top rests with its right end sum_{i >= k} 1/(2i) past the edge.
  for (int k = 1; k <= 4; ++k) {
    double right = 0.0;
    for (int i = k; i <= 4; ++i) right += 1.0 / (2.0 * i);
    s.blocks.push_back({k, 4 - k, right - 1.0});
  }
  return s;
}

double rightmost(const core::Stack& s) {
  double r = -1e9;
  for (const auto& b : s.blocks) r = std::max(r, b.x + 1.0);
  return r;
}

core::Stack shifted(core::Stack s, double dx) {
  for (auto& b : s.blocks) b.x += dx;
  return s;
}

nlohmann::json blocks_json(const core::Stack& s) {
  nlohmann::json out = nlohmann::json::array();
  for (const auto& b : s.blocks) out.push_back({{"id", b.id}, {"row", b.row}, {"x", b.x}});
  return out;
}

// The pile a subject builds for a stabilise problem with the given outcome.
core::Stack answer_pile(const Problem& p, Outcome outcome) {
  double min_x = 0.0;
  for (const auto& b : p.pile.blocks) min_x = std::min(min_x, b.x);
  const Placement aside{0, min_x - 2.0};  // on the surface, touching nothing: changes nothing
  switch (outcome) {
    case Outcome::kCorrect: return with_added(p.pile, p.solution);
    case Outcome::kExcess: {
      std::vector<Placement> more = p.solution;
      more.push_back(aside);
      return with_added(p.pile, more);
    }
    case Outcome::kFailed: return with_added(p.pile, {aside});  // one block, in a place that does not help
  }
  return p.pile;
}

}  // namespace

core::Stack pile_with_score(int32_t score) {
  if (score < 1 || score > 117) throw std::invalid_argument("a scripted pile scores 1..117, not " + std::to_string(score));
  const core::Stack base = score <= 104 ? harmonic_four() : optimum_four();
  // Moving a standing pile left keeps it standing; the overhang becomes exactly score / 100.
  return shifted(base, score / 100.0 - rightmost(base));
}

std::string subject_scenario_json(const SubjectScript& script, const SessionSetup& timing, const Problem& problem1,
                                  const Problem& problem2, const Problem& problem3, uint64_t seed) {
  if (script.answers[2] == Outcome::kExcess) throw std::invalid_argument("the score problem has no excess answer");
  nlohmann::json frames = nlohmann::json::array();
  double t = 0.0;
  auto show = [&](double at, const core::Stack& s) { frames.push_back({{"t", at}, {"blocks", blocks_json(s)}}); };
  const double clear_s = timing.clear_ms / 1000.0;
  const double settle_s = timing.settle_ms / 1000.0;
  // One step: the board empty for clear + 0.5 s, then `pile` from then on for `hold` seconds after the
  // step's latest possible start (the driver starts it within a frame of clear_s).
  auto step = [&](const core::Stack& pile, double hold) {
    show(t, core::Stack{});
    const double start = t + clear_s + 0.2;  // latest start, with two frames of slack
    show(t + clear_s + 0.5, pile);
    t = start + hold;
  };
  const double trial_s = timing.trial_ms / 1000.0;
  step(pile_with_score(script.trial1_score), trial_s + 0.5);
  const Problem* stabilise[2] = {&problem1, &problem2};
  for (int k = 0; k < 2; ++k) {
    const Problem& p = *stabilise[k];
    const Outcome o = script.answers[static_cast<size_t>(k)];
    step(answer_pile(p, o), o == Outcome::kFailed ? p.time_limit_ms / 1000.0 + 0.5 : 0.5 + settle_s + 1.0);
  }
  if (script.answers[2] == Outcome::kCorrect) {
    step(optimum_four(), 0.5 + problem3.hold_ms / 1000.0 + 1.5);
  } else {
    step(pile_with_score(std::max(1, problem3.min_score - 10)), problem3.time_limit_ms / 1000.0 + 0.5);
  }
  step(pile_with_score(script.trial2_score), trial_s + 0.5);
  show(t, core::Stack{});
  std::string description = script.description;
  if (description.empty()) {
    description = "a scripted study subject (bricklayer-study script): games to " + std::to_string(script.trial1_score) +
                  " and " + std::to_string(script.trial2_score) + " points in " +
                  std::to_string(timing.trial_ms / 1000) + " s, problems 1-3 " + to_string(script.answers[0]) + ", " +
                  to_string(script.answers[1]) + ", " + to_string(script.answers[2]);
  }
  nlohmann::json scenario{{"description", description},
                          {"nuisance", "mild"},
                          {"seed", seed},
                          {"duration_s", t + 3.0},
                          {"keyframes", frames}};
  return scenario.dump(1);
}

}  // namespace bricklayer::study
