// The study session driver and projection on one in-process rig, end to end: the projector lights the pile
// under the condition the session asked for (all red while a pile falls under red), every round_t of its
// games carries that condition, the board shows the session's instruction, and key D at the board answers
// a problem ("done"); each stabilise problem's pile is outlined on the board while its step runs.
#include <cmath>
#include <string>

#include <catch2/catch.hpp>

#include <opencv2/imgcodecs.hpp>

#include <SDL.h>

#include "bricklayer/board/board_to_projector.h"
#include "bricklayer/common/channels.h"
#include "bricklayer/core/predict.h"
#include "bricklayer/messages/prediction.h"
#include "bricklayer/messages/stack.h"
#include "bricklayer/projection/projection_node.h"
#include "bricklayer/projector_state_t.hpp"
#include "bricklayer/round_t.hpp"
#include "bricklayer/study/channels.h"
#include "bricklayer/study/problem.h"
#include "bricklayer/study/session_node.h"
#include "bricklayer/study_answer_t.hpp"
#include "harness/rig.h"

using namespace bricklayer;
using namespace std::chrono_literals;
using S = bricklayer::study_session_t;

namespace {

// A stack and the exact annotator's prediction of it (every block's state), as vision and prediction send them.
struct Board {
  harness::Rig& rig;
  int64_t frame = 0;
  void show(const core::Stack& pile) {
    const bricklayer::stack_t s = messages::to_stack_message(pile, rig.now(), ++frame);
    rig.publish(channel(kStackChannel), s);
    bricklayer::prediction_t m{};
    messages::put_verdict(core::predict(pile), m);
    m.utime = s.utime;
    m.frame_number = s.frame_number;
    m.status = bricklayer::prediction_t::STATUS_OK;
    m.verdict = m.balanced ? bricklayer::prediction_t::VERDICT_STABLE : bricklayer::prediction_t::VERDICT_FALLS;
    m.counts_for_max = m.balanced;
    rig.publish(channel(kPredictionChannel), m);
  }
  void hold(const core::Stack& pile, double seconds) {
    for (int k = 0; k < static_cast<int>(seconds * 10); ++k) {
      show(pile);
      rig.run_for(100ms);
    }
  }
};

study::SessionConfig session_config(const std::string& condition) {
  study::SessionConfig c;
  c.subject = "p11";
  c.condition = condition;
  c.session_id = "session-p11";
  const std::string dir = std::string(BRICKLAYER_SOURCE_DIR) + "/launch/problems/";
  c.problem_1 = dir + "stabilise-two.json";
  c.problem_2 = dir + "stabilise-one.json";
  c.problem_3 = dir + "score-100-four.json";
  c.trial_seconds = 10;
  return c;
}

projection::ProjectionConfig projection_config() {
  projection::ProjectionConfig c;
  c.headless = true;
  c.mute = true;
  c.condition = "proposed";  // the exhibit's default: the session must change it
  return c;
}

// The colour (BGR) the projector shows at a board point, in its newest 256-pixel-wide state image.
cv::Vec3b drawn_at(harness::Recorder& rec, double x, double y) {
  const auto states = rec.all<projector_state_t>(channel(kProjectorChannel));
  REQUIRE_FALSE(states.empty());
  const cv::Mat image = cv::imdecode(states.back().image.data, cv::IMREAD_COLOR);
  REQUIRE(image.cols == 256);
  const board::Point2 p = board::BoardToProjector{}.map(x, y);
  return image.at<cv::Vec3b>(static_cast<int>(p.y / 4), static_cast<int>(p.x / 4));
}

// The projector's frame outlines exactly this pile (nothing built on it): each block's bottom edge lit in
// the outline colour just inside, dark just outside and in its middle.
void check_outlined(projection::ProjectionNode& projector, const core::Stack& pile) {
  const projection::ProblemView view = projector.problem_view();
  REQUIRE(view.outlines.size() == pile.blocks.size());
  const cv::Mat frame = projector.display().read_frame();
  const board::BoardToProjector mapping;
  auto at = [&](double x, double y, int dy) {
    const board::Point2 p = mapping.map(x, y);
    return frame.at<cv::Vec3b>(static_cast<int>(std::lround(p.y)) + dy, static_cast<int>(std::lround(p.x)));
  };
  for (size_t k = 0; k < pile.blocks.size(); ++k) {
    const core::Block& b = pile.blocks[k];
    CHECK(view.outlines[k] == projection::ProblemBlock{b.row, b.x});
    const double y0 = b.row / 3.0;
    INFO("block " << b.id << " at row " << b.row << ", x " << b.x);
    const cv::Vec3b on = at(b.x + 0.5, y0, -2);
    CHECK(on == cv::Vec3b(projection::kProblemOutline.b, 0, projection::kProblemOutline.r));
    CHECK(at(b.x + 0.5, y0 + 0.5 / 3.0, 0) == cv::Vec3b(0, 0, 0));
    if (b.row > 0) continue;  // below a row-0 block is the surface, nothing drawn; above it may be another block
    CHECK(at(b.x + 0.5, y0, 3) == cv::Vec3b(0, 0, 0));
  }
}

}  // namespace

TEST_CASE("a study session under red: the projector shows the whole falling pile red, its rounds say red, D answers") {
  harness::Rig rig(10'000);
  // Projection first: the driver tells it the condition as it starts.
  auto& projector = rig.add<projection::ProjectionNode>(projection_config());
  auto& rec = rig.record({channel(kRoundChannel), channel(kProjectorChannel), channel(study::kAnswerChannel),
                          channel(study::kSessionChannel)});
  auto& session = rig.add<study::SessionNode>(session_config("red"));
  rig.step();
  CHECK(projector.condition() == projection::DisplayCondition::kRed);
  CHECK_FALSE(projector.instruction().empty());  // trial 1, ready: the board tells the subject what to do

  Board board{rig};
  board.hold(core::Stack{}, 1.5);  // the clear board the step waits for: trial 1 runs, a round starts
  REQUIRE(session.protocol().step() == S::STEP_TRIAL_1);
  REQUIRE(session.protocol().step_state() == S::STATE_RUNNING);
  REQUIRE(projector.round().state() == projection::RoundState::kRunning);
  const auto running = rec.wait_for<S>(channel(study::kSessionChannel), [](const S& s) {
    return s.step == S::STEP_TRIAL_1 && s.state == S::STATE_RUNNING;
  }, 0ms);
  REQUIRE(running);
  CHECK(projector.instruction() == running->instruction);

  core::Stack falling;
  falling.blocks = {{1, 0, -0.75}, {2, 1, -0.1}};  // the top block tips over block 1's end
  REQUIRE_FALSE(core::predict(falling).balanced);
  board.hold(falling, 1);
  for (const auto& [x, y] : {std::pair{-0.75 + 0.5, 0.5 / 3.0}, std::pair{-0.1 + 0.5, 1.5 / 3.0}}) {
    const cv::Vec3b px = drawn_at(rec, x, y);
    INFO("falling pile under red, block at (" << x << ", " << y << "): BGR " << px);
    CHECK(px[2] > 150);
    CHECK(px[0] == 0);
    CHECK(px[1] == 0);
  }
  core::Stack standing;
  standing.blocks = {{1, 0, -0.75}, {2, 1, -0.45}};
  board.hold(standing, 1);
  for (const auto& [x, y] : {std::pair{-0.75 + 0.5, 0.5 / 3.0}, std::pair{-0.45 + 0.5, 1.5 / 3.0}}) {
    const cv::Vec3b px = drawn_at(rec, x, y);
    INFO("standing pile under red: BGR " << px);
    CHECK(px[0] > 150);
    CHECK(px[2] == 0);
  }
  const auto running_rounds = rec.all<round_t>(channel(kRoundChannel));
  int games = 0;
  for (const round_t& r : running_rounds) {
    if (r.state != round_t::STATE_RUNNING) continue;
    ++games;
    CHECK(r.condition == S::CONDITION_RED);
  }
  CHECK(games >= 2);

  // The game ends; problem 1 runs on a clear board; the subject presses D with nothing built: failed.
  board.hold(standing, 8.5);
  board.hold(core::Stack{}, 1.5);
  REQUIRE(session.protocol().step() == S::STEP_PROBLEM_1);
  REQUIRE(session.protocol().step_state() == S::STATE_RUNNING);
  rig.step();
  CHECK(projector.instruction().find("Say done") != std::string::npos);
  // The pile to build is outlined where the problem file puts its blocks; nothing is built yet.
  const study::Problem problem_1 = study::load_problem(session_config("red").problem_1);
  check_outlined(projector, problem_1.pile);
  SDL_Event e{};
  e.type = SDL_KEYDOWN;
  e.key.keysym.sym = SDLK_d;
  REQUIRE(SDL_PushEvent(&e) == 1);
  const auto answer = rec.wait_for<bricklayer::study_answer_t>(channel(study::kAnswerChannel), {}, 1s);
  REQUIRE(answer);
  CHECK(answer->problem == 1);
  CHECK(answer->outcome == bricklayer::study_answer_t::OUTCOME_FAILED);

  // The answer is taken: problem 1's outlines go at once; problem 2's come when it runs.
  rig.step();
  REQUIRE(session.protocol().step() == S::STEP_PROBLEM_2);
  REQUIRE(session.protocol().step_state() == S::STATE_READY);
  CHECK(projector.problem_view().empty());
  const cv::Mat cleared = projector.display().read_frame();
  for (const core::Block& b : problem_1.pile.blocks) {
    const bricklayer::board::Point2 p = bricklayer::board::BoardToProjector{}.map(b.x + 0.5, b.row / 3.0);
    CHECK(cleared.at<cv::Vec3b>(static_cast<int>(std::lround(p.y)) - 2, static_cast<int>(std::lround(p.x))) ==
          cv::Vec3b(0, 0, 0));
  }
  board.hold(core::Stack{}, 1.5);
  REQUIRE(session.protocol().step_state() == S::STATE_RUNNING);
  check_outlined(projector, study::load_problem(session_config("red").problem_2).pile);
  CHECK(projector.problems_rejected() == 0);
}
