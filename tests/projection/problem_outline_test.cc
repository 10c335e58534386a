// A study problem on the board (problem_outline.h): which problems are refused, where an outline lies,
// when a problem is current; and ProjectionNode on the in-process rig drawing a stabilise problem's pile
// as outlines exactly at the blocks' mapped positions (on the outline, not inside, not just outside, not
// far away), under a real block's verdict, gone when the problem is no longer republished or the session
// ends; a score problem's target line counting down on the rig's clock (frozen while paused); malformed
// problems, and ones whose num_blocks disagrees with the blocks sent (which cannot decode), counted and
// nothing drawn.
#include <cmath>
#include <limits>
#include <vector>

#include <catch2/catch.hpp>

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "bricklayer/board/board_to_projector.h"
#include "bricklayer/common/channels.h"
#include "bricklayer/projection/problem_outline.h"
#include "bricklayer/projection/projection_node.h"
#include "bricklayer/runtime/codec.h"
#include "harness/rig.h"

using namespace bricklayer;
using namespace bricklayer::projection;
using namespace std::chrono_literals;
using S = study_session_t;
using P = study_problem_t;

namespace {

constexpr int64_t kStepUs = 10'000;
constexpr int64_t kS = 1'000'000;
constexpr double kHeight = 1.0 / 3.0;  // the block height of the node's board (no stack seen, and the tests' stacks)

block_t block(int64_t id, int row, double x) {
  block_t b{};
  b.id = id;
  b.row = row;
  b.x = x;
  return b;
}

// Problem 1 of the study (launch/problems/stabilise-two.json): two towers whose top blocks tip.
P stabilise_problem(const std::string& session = "s07") {
  P p{};
  p.session_id = session;
  p.problem = 1;
  p.name = "stabilise-two";
  p.kind = P::KIND_STABILISE;
  p.instruction = "Build the pile shown by the outlines.";
  p.time_limit_ms = 180'000;
  p.minimum_added = 2;
  p.blocks = {block(1, 0, -2.6), block(2, 1, -1.95), block(3, 0, -0.8), block(4, 1, -0.2)};
  p.num_blocks = static_cast<int32_t>(p.blocks.size());
  return p;
}

P score_problem(const std::string& session = "s07") {
  P p{};
  p.session_id = session;
  p.problem = 3;
  p.name = "score-100-four";
  p.kind = P::KIND_SCORE;
  p.instruction = "Use at most four blocks. Make the pile reach at least 100 points within one minute.";
  p.time_limit_ms = 60'000;
  p.minimum_added = -1;
  p.min_score = 100;
  p.max_blocks = 4;
  return p;
}

S session_on(int8_t step, int8_t state, const std::string& id = "s07") {
  S s{};
  s.session_id = id;
  s.subject_id = "p07";
  s.condition = S::CONDITION_PROPOSED;
  s.step = step;
  s.state = state;
  s.attempt = 1;
  return s;
}

ProjectionConfig node_config() {
  ProjectionConfig c;
  c.headless = true;
  c.mute = true;
  c.stale_seconds = 0;  // no camera in these tests: nothing but the study changes the display
  return c;
}

bool black(const cv::Vec3b& px) { return px[0] == 0 && px[1] == 0 && px[2] == 0; }
bool outline_colour(const cv::Vec3b& px) {
  return px[1] == 0 && std::abs(px[2] - kProblemOutline.r) <= 2 && std::abs(px[0] - kProblemOutline.b) <= 2;
}
bool blue(const cv::Vec3b& px) { return px[0] > 150 && px[1] == 0 && px[2] == 0; }

// Probes of one block's outline in projector pixels (pixel centres at integers, as the mapping gives):
// the middle of each side 2 px inside the block (on the outline, 5 px thick at 768 lines), 3 px outside it,
// and the block's centre.
struct Probes {
  std::vector<cv::Point> on, outside;
  cv::Point centre;
};
Probes probes(const board::BoardToProjector& m, const block_t& b) {
  const double y0 = b.row * kHeight, y1 = y0 + kHeight, ym = (y0 + y1) / 2;
  auto px = [](board::Point2 p, double dx, double dy) {
    return cv::Point(static_cast<int>(std::lround(p.x + dx)), static_cast<int>(std::lround(p.y + dy)));
  };
  Probes r;
  // Board y grows upwards, projector rows downwards.
  const board::Point2 bottom = m.map(b.x + 0.5, y0), top = m.map(b.x + 0.5, y1), left = m.map(b.x, ym),
                      right = m.map(b.x + 1, ym);
  r.on = {px(bottom, 0, -2), px(top, 0, 2), px(left, 2, 0), px(right, -2, 0)};
  r.outside = {px(bottom, 0, 3), px(top, 0, -3), px(left, -3, 0), px(right, 3, 0)};
  r.centre = px(m.map(b.x + 0.5, ym), 0, 0);
  return r;
}

// A stack of these blocks with every block stable, as vision and prediction would send it.
void show_stack(harness::Rig& rig, int64_t frame, const std::vector<block_t>& blocks) {
  bricklayer::stack_t s{};
  s.utime = rig.now();
  s.frame_number = frame;
  s.block_length = 1;
  s.block_height = kHeight;
  s.status = bricklayer::stack_t::STATUS_OK;
  s.blocks = blocks;
  s.num_blocks = static_cast<int32_t>(blocks.size());
  prediction_t p{};
  p.utime = s.utime;
  p.frame_number = frame;
  p.status = prediction_t::STATUS_OK;
  p.balanced = true;
  for (const block_t& b : blocks) {
    block_prediction_t bp{};
    bp.id = b.id;
    bp.state = block_prediction_t::STATE_STABLE;
    p.blocks.push_back(bp);
  }
  p.num_blocks = static_cast<int32_t>(p.blocks.size());
  rig.publish(channel(kStackChannel), s);
  rig.publish(channel(kPredictionChannel), p);
}

}  // namespace

TEST_CASE("a study problem that cannot be drawn is refused with the reason") {
  CHECK(problem_fault(stabilise_problem()).empty());
  CHECK(problem_fault(score_problem()).empty());
  auto refused = [](P p, const std::string& words) {
    const std::string fault = problem_fault(p);
    INFO("fault: " << fault);
    CHECK(fault.find(words) != std::string::npos);
  };
  P p = stabilise_problem();
  p.num_blocks = 5;
  refused(p, "num_blocks 5 disagrees");
  p = stabilise_problem();
  p.blocks[2].x = std::numeric_limits<double>::quiet_NaN();
  refused(p, "block 3 has x");
  p = stabilise_problem();
  p.blocks[0].x = std::numeric_limits<double>::infinity();
  refused(p, "block 1 has x");
  p = stabilise_problem();
  p.blocks[1].x = 1e4;
  refused(p, "block 2 has x");
  p = stabilise_problem();
  p.blocks[3].row = kMaxProblemRow + 1;
  refused(p, "block 4 has row 101");
  p = stabilise_problem();
  p.blocks[3].row = -1;
  refused(p, "has row -1");
  p = stabilise_problem();
  p.blocks.clear();
  p.num_blocks = 0;
  refused(p, "without blocks");
  p = stabilise_problem();
  p.kind = 7;
  refused(p, "unknown kind 7");
  p = stabilise_problem();
  p.problem = 4;
  refused(p, "not 1, 2 or 3");
  p = stabilise_problem();
  p.time_limit_ms = -1;
  refused(p, "negative time limit");
  p = score_problem();
  p.max_blocks = 0;
  refused(p, "max_blocks 0");
  p = score_problem();
  p.min_score = -100;
  refused(p, "negative min_score");
  // A row at the limit and an x far off the board are still drawable (off the projector, clipped).
  p = stabilise_problem();
  p.blocks[0].row = kMaxProblemRow;
  p.blocks[1].x = -kMaxProblemX;
  CHECK(problem_fault(p).empty());
}

TEST_CASE("an outline lies just inside the block's mapped edges, as thick as asked") {
  const board::BoardToProjector m;
  const ProblemBlock b{1, -1.95};
  const auto ring = outline_ring(b, kHeight, m, 5.0);
  const double y0 = kHeight, y1 = 2 * kHeight;
  const board::Point2 outer[4] = {m.map(-1.95, y0), m.map(-0.95, y0), m.map(-0.95, y1), m.map(-1.95, y1)};
  for (int k = 0; k < 4; ++k) {
    // Each side's first two corners are the block's own mapped corners, in order around the block.
    CHECK(ring[k][0].x == Approx(outer[k].x));
    CHECK(ring[k][0].y == Approx(outer[k].y));
    CHECK(ring[k][1].x == Approx(outer[(k + 1) % 4].x));
    CHECK(ring[k][1].y == Approx(outer[(k + 1) % 4].y));
  }
  // The inner edge 5 px in: bottom side up, right side left, top side down, left side right.
  CHECK(ring[0][3].y == Approx(outer[0].y - 5));
  CHECK(ring[0][3].x == Approx(outer[0].x + 5));
  CHECK(ring[1][2].x == Approx(outer[2].x - 5));
  CHECK(ring[2][2].y == Approx(outer[3].y + 5));
  CHECK(ring[3][3].x == Approx(outer[0].x + 5));
  // Thicker than the block: the ring closes in the middle instead of crossing over.
  const auto solid = outline_ring(b, kHeight, m, 100.0);
  CHECK(solid[0][3].y == Approx(m.map(-1.95, y0 + kHeight / 2).y));
}

TEST_CASE("a problem is current while its session is heard on its step, running or paused") {
  ProblemOutline outline;
  const int64_t t0 = 1'000 * kS;
  CHECK(outline.take(stabilise_problem(), t0).empty());
  S running = session_on(S::STEP_PROBLEM_1, S::STATE_RUNNING);
  CHECK(outline.view(t0, nullptr, 0).empty());  // no session heard
  const ProblemView shown = outline.view(t0, &running, t0);
  REQUIRE(shown.outlines.size() == 4);
  CHECK(shown.outlines[1] == ProblemBlock{1, -1.95});
  CHECK(shown.target.empty());
  CHECK(outline.view(t0 + 3 * kS, &running, t0) == shown);  // 3 s: still heard
  CHECK(outline.view(t0 + 3 * kS + 1, &running, t0 + 3 * kS).empty());  // the problem not republished
  CHECK(outline.view(t0 + 3 * kS + 1, &running, t0).empty());  // neither is the session
  S paused = session_on(S::STEP_PROBLEM_1, S::STATE_PAUSED);
  CHECK(outline.view(t0, &paused, t0) == shown);
  for (int8_t state : {S::STATE_READY, S::STATE_FINISHED, S::STATE_ABORTED}) {
    S other = session_on(S::STEP_PROBLEM_1, state);
    CHECK(outline.view(t0, &other, t0).empty());
  }
  S next_step = session_on(S::STEP_PROBLEM_2, S::STATE_RUNNING);
  CHECK(outline.view(t0, &next_step, t0).empty());
  S other_session = session_on(S::STEP_PROBLEM_1, S::STATE_RUNNING, "s08");
  CHECK(outline.view(t0, &other_session, t0).empty());

  // The newest wins: a malformed problem drops the one before it.
  P bad = stabilise_problem();
  bad.num_blocks = 9;
  CHECK_FALSE(outline.take(bad, t0 + kS).empty());
  CHECK(outline.view(t0 + kS, &running, t0 + kS).empty());
  CHECK(outline.problem() == nullptr);

  // A score problem: its target, the time left counted down from the session's, frozen while paused.
  CHECK(outline.take(score_problem(), t0).empty());
  S score = session_on(S::STEP_PROBLEM_3, S::STATE_RUNNING);
  score.step_duration_ms = 60'000;
  score.step_remaining_ms = 42'000;
  CHECK(outline.view(t0, &score, t0).target == "TARGET 100 points with at most 4 blocks - 0:42 left");
  CHECK(outline.view(t0 + 1, &score, t0).target == "TARGET 100 points with at most 4 blocks - 0:42 left");
  CHECK(outline.view(t0 + 2 * kS + 1, &score, t0).target == "TARGET 100 points with at most 4 blocks - 0:40 left");
  CHECK(outline.view(t0 + 2 * kS + 1, &score, t0).outlines.empty());
  score.state = S::STATE_PAUSED;
  CHECK(outline.view(t0 + 2 * kS + 1, &score, t0).target == "TARGET 100 points with at most 4 blocks - 0:42 left");
  score.state = S::STATE_RUNNING;
  score.step_remaining_ms = 500;
  CHECK(outline.view(t0 + kS, &score, t0).target == "TARGET 100 points with at most 4 blocks - 0:00 left");
  P unlimited = score_problem();
  unlimited.time_limit_ms = 0;
  unlimited.max_blocks = 1;
  CHECK(outline.take(unlimited, t0).empty());
  CHECK(outline.view(t0, &score, t0).target == "TARGET 100 points with at most 1 block");
}

TEST_CASE("on the rig a stabilise problem's pile is outlined exactly where its blocks map, under the real blocks") {
  harness::Rig rig(kStepUs);
  auto& node = rig.add<ProjectionNode>(node_config());
  const board::BoardToProjector mapping;  // the node's uncalibrated default
  S session = session_on(S::STEP_PROBLEM_1, S::STATE_RUNNING);
  session.instruction = "Build the pile shown by the outlines. Say done when you are finished.";
  const P problem = stabilise_problem();
  int64_t problem_sent = 0;
  // The driver's once-a-second messages: the session always, the problem while `with_problem`.
  auto driver = [&](int seconds, bool with_problem) {
    for (int k = 0; k < seconds; ++k) {
      session.utime = rig.now();
      rig.publish(channel(kStudySessionChannel), session);
      if (with_problem) {
        P p = problem;
        p.utime = problem_sent = rig.now();
        rig.publish(channel(kStudyProblemChannel), p);
      }
      rig.run_for(1s);
    }
  };
  driver(1, false);
  const cv::Mat before = node.display().read_frame();
  CHECK(node.problem_view().empty());
  CHECK(node.layout().problem_outlines.w == 0);
  for (const block_t& b : problem.blocks) {
    const Probes pr = probes(mapping, b);
    for (const cv::Point& q : pr.on) CHECK(black(before.at<cv::Vec3b>(q)));
  }

  driver(2, true);
  REQUIRE(node.problem_view().outlines.size() == 4);
  const cv::Mat shown = node.display().read_frame();
  for (const block_t& b : problem.blocks) {
    const Probes pr = probes(mapping, b);
    for (const cv::Point& q : pr.on) {
      INFO("block " << b.id << " on its outline at " << q << ": BGR " << shown.at<cv::Vec3b>(q));
      CHECK(outline_colour(shown.at<cv::Vec3b>(q)));
    }
    for (const cv::Point& q : pr.outside) {
      INFO("block " << b.id << " just outside at " << q << ": BGR " << shown.at<cv::Vec3b>(q));
      CHECK(black(shown.at<cv::Vec3b>(q)));
    }
    INFO("block " << b.id << " centre " << pr.centre);
    CHECK(black(shown.at<cv::Vec3b>(pr.centre)));
  }
  // Far away (a block length above the pile, right of the edge, the surface below) nothing is lit.
  for (const auto& [x, y] : {std::pair{-1.0, 1.8}, std::pair{1.5, 0.2}, std::pair{-1.0, -0.3}}) {
    const board::Point2 p = mapping.map(x, y);
    CHECK(black(shown.at<cv::Vec3b>(cv::Point(static_cast<int>(std::lround(p.x)), static_cast<int>(std::lround(p.y))))));
  }
  // Only where the outlines are did the frame change, and green stays 0 everywhere.
  cv::Mat changed;
  cv::absdiff(before, shown, changed);
  cv::cvtColor(changed, changed, cv::COLOR_BGR2GRAY);
  const SDL_Rect box = node.layout().problem_outlines;
  CHECK(cv::countNonZero(changed) > 0);
  CHECK(cv::countNonZero(changed(cv::Rect(box.x, box.y, box.w, box.h))) == cv::countNonZero(changed));
  const board::Point2 first = mapping.map(-2.6, 0), last = mapping.map(0.8, 2 * kHeight);
  CHECK(box.x == Approx(first.x).margin(1.5));
  CHECK(box.y + box.h == Approx(first.y).margin(1.5));
  CHECK(box.x + box.w == Approx(last.x).margin(1.5));
  CHECK(box.y == Approx(last.y).margin(1.5));
  cv::Mat green;
  cv::extractChannel(shown, green, 1);
  CHECK(cv::countNonZero(green) == 0);

  // The subject puts block 1 in place: its verdict covers its outline; the others stay outlined.
  show_stack(rig, 1, {block(11, 0, -2.6)});
  driver(1, true);
  const cv::Mat placed = node.display().read_frame();
  for (const cv::Point& q : probes(mapping, problem.blocks[0]).on) {
    INFO("block 1 placed, its outline at " << q << ": BGR " << placed.at<cv::Vec3b>(q));
    CHECK(blue(placed.at<cv::Vec3b>(q)));
  }
  CHECK(blue(placed.at<cv::Vec3b>(probes(mapping, problem.blocks[0]).centre)));
  for (size_t k = 1; k < problem.blocks.size(); ++k)
    for (const cv::Point& q : probes(mapping, problem.blocks[k]).on) CHECK(outline_colour(placed.at<cv::Vec3b>(q)));
  show_stack(rig, 2, {});
  driver(1, true);

  // No longer republished while the session still is: gone on the first step past 3 s, not before.
  driver(2, false);
  CHECK_FALSE(node.problem_view().empty());
  rig.run_until([&] { return node.problem_view().empty(); }, 5s);
  CHECK(node.problem_view().empty());
  CHECK(rig.now() == problem_sent + ProblemOutline::kHeardUs + kStepUs);
  session.utime = rig.now();
  rig.publish(channel(kStudySessionChannel), session);
  rig.step();
  CHECK(cv::norm(before, node.display().read_frame(), cv::NORM_L1) == 0);

  // Back, then the experimenter aborts: gone with the session's next message, at once.
  driver(1, true);
  REQUIRE_FALSE(node.problem_view().empty());
  session.state = S::STATE_ABORTED;
  session.instruction = "";
  session.utime = rig.now();
  rig.publish(channel(kStudySessionChannel), session);
  rig.step();
  CHECK(node.problem_view().empty());
  const cv::Mat aborted = node.display().read_frame();
  for (const block_t& b : problem.blocks)
    for (const cv::Point& q : probes(mapping, b).on) CHECK(black(aborted.at<cv::Vec3b>(q)));

  // And when the driver falls silent altogether (it stops 2 s after the session is over).
  session.state = S::STATE_RUNNING;
  driver(1, true);
  REQUIRE_FALSE(node.problem_view().empty());
  const int64_t last_heard = rig.now() - 1 * kS;
  rig.run_until([&] { return node.problem_view().empty(); }, 5s);
  CHECK(rig.now() == last_heard + ProblemOutline::kHeardUs + kStepUs);
  rig.step();
  const cv::Mat silent = node.display().read_frame();
  for (const block_t& b : problem.blocks)
    for (const cv::Point& q : probes(mapping, b).on) CHECK(black(silent.at<cv::Vec3b>(q)));
  CHECK(node.problems_rejected() == 0);
}

TEST_CASE("on the rig a score problem shows its target under the instruction, its time left on the rig's clock") {
  harness::Rig rig(kStepUs);
  auto& node = rig.add<ProjectionNode>(node_config());
  S session = session_on(S::STEP_PROBLEM_3, S::STATE_RUNNING);
  session.instruction = score_problem().instruction;
  session.step_duration_ms = 60'000;
  const int64_t start = rig.now();
  auto driver = [&](int seconds, bool with_problem) {
    for (int k = 0; k < seconds; ++k) {
      session.utime = rig.now();
      if (session.state == S::STATE_RUNNING) session.step_remaining_ms = 60'000 - (rig.now() - start) / 1000;
      rig.publish(channel(kStudySessionChannel), session);
      if (with_problem) {
        P p = score_problem();
        p.utime = rig.now();
        rig.publish(channel(kStudyProblemChannel), p);
      }
      rig.run_for(1s);
    }
  };
  session.step_remaining_ms = 60'000;
  rig.publish(channel(kStudySessionChannel), session);
  rig.step();
  const cv::Mat before = node.display().read_frame();
  const SDL_Rect instruction = node.layout().instruction;
  REQUIRE(instruction.w > 0);
  CHECK(node.layout().problem_target.w == 0);

  P p = score_problem();
  p.utime = rig.now();
  rig.publish(channel(kStudyProblemChannel), p);
  rig.step();
  CHECK(node.problem_view().target == "TARGET 100 points with at most 4 blocks - 1:00 left");
  CHECK(node.problem_view().outlines.empty());
  const SDL_Rect target = node.layout().problem_target;
  REQUIRE(target.w > 0);
  CHECK(target.y >= instruction.y + instruction.h);  // under the instruction, centred
  CHECK(std::abs(target.x + target.w / 2 - node.display().width() / 2) <= 1);
  const cv::Mat shown = node.display().read_frame();
  const cv::Rect area(target.x, target.y, target.w, target.h);
  cv::Mat grey;
  cv::cvtColor(before(area), grey, cv::COLOR_BGR2GRAY);
  CHECK(cv::countNonZero(grey) == 0);  // nothing there before
  cv::cvtColor(shown(area), grey, cv::COLOR_BGR2GRAY);
  CHECK(cv::countNonZero(grey) > target.w * target.h / 20);  // the words
  cv::Mat green;
  cv::extractChannel(shown, green, 1);
  CHECK(cv::countNonZero(green) == 0);

  driver(3, true);
  CHECK(node.problem_view().target == "TARGET 100 points with at most 4 blocks - 0:57 left");
  session.step_remaining_ms = 60'000 - (rig.now() - start) / 1000;  // as the driver pauses: 56.98 s left
  session.state = S::STATE_PAUSED;  // the step's clock stands still
  driver(2, true);
  CHECK(node.problem_view().target == "TARGET 100 points with at most 4 blocks - 0:57 left");

  // The step over (the next one is the second game): gone with the session's message.
  session.step = S::STEP_TRIAL_2;
  session.state = S::STATE_READY;
  session.utime = rig.now();
  rig.publish(channel(kStudySessionChannel), session);
  rig.step();
  CHECK(node.problem_view().empty());
  CHECK(node.layout().problem_target.w == 0);
  cv::cvtColor(node.display().read_frame()(area), grey, cv::COLOR_BGR2GRAY);
  CHECK(cv::countNonZero(grey) == 0);
}

TEST_CASE("on the rig a malformed study problem is counted and draws nothing") {
  harness::Rig rig(kStepUs);
  auto& node = rig.add<ProjectionNode>(node_config());
  S session = session_on(S::STEP_PROBLEM_1, S::STATE_RUNNING);
  session.instruction = "Build the pile shown by the outlines.";
  auto hear_session = [&] {
    session.utime = rig.now();
    rig.publish(channel(kStudySessionChannel), session);
  };
  hear_session();
  rig.run_for(100ms);
  const cv::Mat before = node.display().read_frame();
  const int64_t errors_before = node.counters().errors;

  // Problems that decode but cannot be drawn: refused by problem_fault, counted by the node.
  std::vector<P> bad;
  P p = stabilise_problem();
  p.blocks.clear();
  p.num_blocks = 0;
  bad.push_back(p);
  p = stabilise_problem();
  p.blocks[1].x = std::numeric_limits<double>::quiet_NaN();
  bad.push_back(p);
  p = stabilise_problem();
  p.blocks[2].x = -std::numeric_limits<double>::infinity();
  bad.push_back(p);
  p = stabilise_problem();
  p.blocks[3].row = 5000;
  bad.push_back(p);
  p = stabilise_problem();
  p.kind = 0;
  bad.push_back(p);
  p = stabilise_problem();
  p.problem = 0;
  bad.push_back(p);
  for (const P& m : bad) {
    rig.publish(channel(kStudyProblemChannel), m);
    rig.run_for(100ms);
    CHECK(node.problem_view().empty());
  }
  CHECK(node.problems_rejected() == 6);
  CHECK(node.counters().errors - errors_before == 6);
  CHECK(cv::norm(before, node.display().read_frame(), cv::NORM_L1) == 0);

  // On the wire a num_blocks that disagrees with the blocks sent cannot decode (the encoder writes
  // num_blocks blocks): four blocks sent, num_blocks patched to 5 and to -1; and bytes that are no
  // study_problem_t at all. The runtime counts each; the display goes on.
  std::vector<uint8_t> bytes = runtime::encode(stabilise_problem());
  const P good = stabilise_problem();
  // fingerprint, utime, session_id, problem, name, kind, instruction, time_limit_ms, minimum_added
  const size_t num_blocks_at = 8 + 8 + (4 + good.session_id.size() + 1) + 1 + (4 + good.name.size() + 1) + 1 +
                               (4 + good.instruction.size() + 1) + 8 + 4;
  REQUIRE(bytes.size() > num_blocks_at + 4);
  REQUIRE(bytes[num_blocks_at + 3] == 4);  // big-endian 4
  for (uint8_t last : {uint8_t{5}, uint8_t{0xff}}) {
    std::vector<uint8_t> patched = bytes;
    patched[num_blocks_at + 3] = last;
    if (last == 0xff) patched[num_blocks_at] = patched[num_blocks_at + 1] = patched[num_blocks_at + 2] = 0xff;
    rig.publish_bytes(channel(kStudyProblemChannel), patched);
    rig.run_for(100ms);
  }
  rig.publish_bytes(channel(kStudyProblemChannel), {0x42, 0x00, 0x13, 0x37});
  rig.run_for(100ms);
  CHECK(node.counters().errors - errors_before == 9);
  CHECK(node.problems_rejected() == 6);
  CHECK(node.problem_view().empty());
  CHECK(cv::norm(before, node.display().read_frame(), cv::NORM_L1) == 0);

  // A good problem is drawn; a malformed one after it takes its place: nothing is drawn.
  rig.publish(channel(kStudyProblemChannel), stabilise_problem());
  rig.run_for(100ms);
  REQUIRE(node.problem_view().outlines.size() == 4);
  CHECK(cv::norm(before, node.display().read_frame(), cv::NORM_L1) > 0);
  rig.publish(channel(kStudyProblemChannel), bad.front());
  rig.run_for(100ms);
  CHECK(node.problem_view().empty());
  CHECK(node.problems_rejected() == 7);
  CHECK(cv::norm(before, node.display().read_frame(), cv::NORM_L1) == 0);
}
