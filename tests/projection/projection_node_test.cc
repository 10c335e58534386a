// ProjectionNode on the in-process rig: the whole module (bus, rounds, round book, staleness, drawing)
// on a clock that moves only when the test steps it, so every moment is exact: a round starts the
// instant the hold is over, ends exactly at its duration, a node built again on the same round book
// (a restart) runs the same round on, stale inputs turn the heartbeat and the drawn blocks, and bad
// configurations are refused; the keys (S, R, H, C, D, P, Q) as SDL delivers them; the display condition
// from the flag, SET_CONDITION, key C and a study session, carried by every round_t; the study session's
// instruction shown while its driver is heard.
#include <catch2/catch.hpp>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <nlohmann/json.hpp>

#include <SDL.h>

#include "bricklayer/board/board_to_projector.h"
#include "bricklayer/command_t.hpp"
#include "bricklayer/common/channels.h"
#include "bricklayer/projection/projection_node.h"
#include "bricklayer/projector_state_t.hpp"
#include "bricklayer/round_t.hpp"
#include "bricklayer/study_command_t.hpp"
#include "bricklayer/study_session_t.hpp"
#include "harness/rig.h"
#include "harness/scratch.h"

using namespace bricklayer;
using namespace bricklayer::projection;
using namespace std::chrono_literals;

namespace {

constexpr int64_t kStepUs = 10'000;
constexpr int64_t kS = 1'000'000;

ProjectionConfig quick_config(const std::string& rounds_file) {
  ProjectionConfig c;
  c.headless = true;
  c.mute = true;
  c.rounds_file = rounds_file;
  c.round_seconds = 5;
  c.round_start_hold = 2;
  c.round_arm_empty = 1;
  c.round_end_empty = 3;
  c.stale_seconds = 1;
  return c;
}

struct Camera {
  harness::Rig& rig;
  int64_t frame = 0;
  bool pile = false;
  bool balanced = true;
  bool predictions = true;

  // One stack (and its prediction) now, as vision and prediction would answer.
  void send() {
    ++frame;
    bricklayer::stack_t s{};
    s.utime = rig.now();
    s.frame_number = frame;
    s.block_length = 1;
    s.block_height = 1.0 / 3.0;
    s.status = bricklayer::stack_t::STATUS_OK;
    prediction_t p{};
    p.utime = s.utime;
    p.frame_number = frame;
    p.status = prediction_t::STATUS_OK;
    p.balanced = true;
    if (pile) {
      for (auto [id, row, x] : {std::tuple<int64_t, int, double>{1, 0, -0.8}, {2, 1, -0.7}}) {
        block_t b{};
        b.id = id;
        b.row = row;
        b.x = x;
        b.confidence = 1;
        s.blocks.push_back(b);
        block_prediction_t bp{};
        bp.id = id;
        bp.state = balanced || id == 1 ? block_prediction_t::STATE_STABLE : block_prediction_t::STATE_CAUSE;
        p.blocks.push_back(bp);
      }
      p.balanced = balanced;
      p.score = 30;
    }
    s.num_blocks = static_cast<int32_t>(s.blocks.size());
    p.num_blocks = static_cast<int32_t>(p.blocks.size());
    rig.publish(channel(kStackChannel), s);
    if (predictions) rig.publish(channel(kPredictionChannel), p);
  }
  // Stacks at 10 Hz for this long (rig time).
  void run(int64_t us) {
    const int64_t end = rig.now() + us;
    while (rig.now() < end) {
      send();
      for (int k = 0; k < 10; ++k) rig.step();
    }
  }
};

}  // namespace

TEST_CASE("on the rig a round starts the instant the hold is over and ends exactly at its duration") {
  harness::ScratchDir dir("projection-node");
  harness::Rig rig(kStepUs);
  // In a folder that does not exist yet (a fresh install's logs/): made when the node starts.
  auto& node = rig.add<ProjectionNode>(quick_config((dir / "logs" / "rounds.json").string()));
  CHECK(std::filesystem::is_directory(dir / "logs"));
  auto& rec = rig.record({channel(kRoundChannel)});
  Camera cam{rig};
  cam.run(2 * kS);  // an empty board: armed
  CHECK(node.round().state() == RoundState::kIdle);
  cam.pile = true;
  const int64_t placed = rig.now();
  cam.run(3 * kS);
  const auto running = rec.wait_for<round_t>(channel(kRoundChannel), [](const round_t& r) { return r.state == round_t::STATE_RUNNING; }, 0ms);
  REQUIRE(running);
  CHECK(running->utime == placed + 2 * kS);  // not a step earlier or later
  CHECK(running->remaining_ms == 5000);
  REQUIRE(node.round().running());
  CHECK(node.round().running()->start_utime == placed + 2 * kS);
  CHECK(node.round().max_score() == 30);

  cam.run(4500 * 1000);
  const auto ended = rec.wait_for<round_t>(channel(kRoundChannel), [](const round_t& r) { return r.state == round_t::STATE_ENDED; }, 0ms);
  REQUIRE(ended);
  CHECK(ended->utime == placed + 7 * kS);
  CHECK(ended->max_score == 30);
  const nlohmann::json book = nlohmann::json::parse(harness::read_file(dir / "logs" / "rounds.json"));
  REQUIRE(book["rounds"].size() == 1);
  CHECK(book["rounds"][0]["start_utime"] == placed + 2 * kS);
  CHECK(book["rounds"][0]["end_utime"] == placed + 7 * kS);
  CHECK(book["rounds"][0]["end"] == "time up");
  CHECK(book["rounds"][0]["blocks"] == 2);
}

TEST_CASE("on the rig a node built again on the same round book runs the same round on") {
  harness::ScratchDir dir("projection-node-restart");
  const std::string file = (dir / "rounds.json").string();
  int64_t started = 0;
  {
    harness::Rig rig(kStepUs);
    auto& node = rig.add<ProjectionNode>(quick_config(file));
    Camera cam{rig};
    cam.run(2 * kS);
    cam.pile = true;
    cam.run(2500 * 1000);
    REQUIRE(node.round().state() == RoundState::kRunning);
    started = node.round().running()->start_utime;
  }  // gone without a word, as a process killed with -9
  harness::Rig rig(kStepUs, started + 3 * kS);  // back 3 s into the round
  auto& node = rig.add<ProjectionNode>(quick_config(file));
  auto& rec = rig.record({channel(kRoundChannel)});
  rig.step();
  const auto r = rec.wait_for<round_t>(channel(kRoundChannel), {}, 0ms);
  REQUIRE(r);
  CHECK(r->state == round_t::STATE_RUNNING);
  CHECK(r->max_score == 30);
  CHECK(r->remaining_ms == 2000 - kStepUs / 1000);
  CHECK(node.round().running()->start_utime == started);
  // It still ends on time, by its original start.
  Camera cam{rig};
  cam.pile = true;
  cam.run(2 * kS);
  REQUIRE(node.round().last_round());
  CHECK(node.round().last_round()->end_utime == started + 5 * kS);
}

TEST_CASE("on the rig stale inputs turn the heartbeat and take the verdict colours off the blocks") {
  harness::Rig rig(kStepUs);
  auto& node = rig.add<ProjectionNode>(quick_config(""));
  auto& rec = rig.record({channel(kHeartbeatChannel), channel(kProjectorChannel)});
  Camera cam{rig};
  cam.pile = true;
  cam.balanced = false;  // the top block is the cause: red
  cam.run(2 * kS);
  CHECK(node.input_problem() == InputProblem::kNone);
  auto red_drawn = [&rec](bool red) {
    const auto states = rec.all<projector_state_t>(channel(kProjectorChannel));
    REQUIRE_FALSE(states.empty());
    const cv::Mat image = cv::imdecode(states.back().image.data, cv::IMREAD_COLOR);
    REQUIRE(image.cols == 256);
    const board::Point2 top = board::BoardToProjector{}.map(-0.7 + 0.5, 1.5 / 3.0);
    const cv::Vec3b px = image.at<cv::Vec3b>(static_cast<int>(top.y / 4), static_cast<int>(top.x / 4));
    INFO("the cause's pixel BGR " << px);
    CHECK((px[2] > 150) == red);
    CHECK(px[1] == 0);
  };
  red_drawn(true);

  rec.clear();
  const int64_t last_stack = rig.now() - 10 * kStepUs;
  rig.run_until([&] { return node.input_problem() != InputProblem::kNone; }, 3s);
  CHECK(node.input_problem() == InputProblem::kCameraNotSeeing);
  CHECK(rig.now() == last_stack + kS + kStepUs);  // the first step past the limit
  const auto hb = rec.wait_for_heartbeat("projection", [](const heartbeat_t& h) { return h.status != "ok"; }, 2s);
  REQUIRE(hb);
  CHECK(hb->status.rfind("camera not seeing: no stacks for", 0) == 0);
  red_drawn(false);

  cam.predictions = false;
  rec.clear();
  cam.run(2 * kS);
  CHECK(node.input_problem() == InputProblem::kWaitingForOtherMachine);
  const auto hb2 = rec.wait_for_heartbeat("projection", [](const heartbeat_t& h) { return h.status != "ok"; }, 0ms);
  REQUIRE(hb2);
  CHECK(hb2->status.rfind("waiting for the other machine: no predictions for", 0) == 0);
  cam.predictions = true;
  cam.run(1 * kS);
  CHECK(node.input_problem() == InputProblem::kNone);
  red_drawn(true);
}

TEST_CASE("on the rig the keys start and reset rounds, ask for a hint, take a snapshot and quit") {
  harness::ScratchDir dir("projection-node-keys");
  harness::Rig rig(kStepUs);
  ProjectionConfig config = quick_config((dir / "rounds.json").string());
  config.snapshot_dir = (dir / "shots").string();
  auto& node = rig.add<ProjectionNode>(config);
  auto& rec = rig.record({channel(kCommandChannel)});
  auto press = [&rig](SDL_Keycode key) {
    SDL_Event e{};
    e.type = SDL_KEYDOWN;
    e.key.keysym.sym = key;
    REQUIRE(SDL_PushEvent(&e) == 1);
    rig.step();
  };
  rig.step();
  press(SDLK_s);  // a round on a board never seen: only a key (or START_ROUND) does that
  REQUIRE(node.round().state() == RoundState::kRunning);
  CHECK(node.round().running()->start_utime == rig.now());
  press(SDLK_r);
  CHECK(node.round().state() == RoundState::kIdle);
  REQUIRE(node.round().last_round());
  CHECK(node.round().last_round()->end == RoundEnd::kReset);
  press(SDLK_h);
  const auto hint = rec.wait_for<command_t>(channel(kCommandChannel), [](const command_t& c) { return c.command == command_t::REQUEST_HINT; }, 0ms);
  REQUIRE(hint);
  CHECK(hint->sequence == 1);
  press(SDLK_p);
  CHECK(std::filesystem::exists(dir / "shots" / "snapshot-0001.png"));
  CHECK_FALSE(node.quit_requested());
  press(SDLK_q);
  CHECK(node.quit_requested());
}

TEST_CASE("on the rig a damaged round book is kept aside, counted, and a new one starts") {
  harness::ScratchDir dir("projection-node-damaged");
  const std::string file = (dir / "rounds.json").string();
  harness::write_file(file, "{\"version\": 1, \"rounds\": [{\"start_ut");  // torn by hand
  harness::Rig rig(kStepUs);
  auto& node = rig.add<ProjectionNode>(quick_config(file));
  CHECK(node.counters().errors == 1);
  CHECK(harness::read_file(file + ".damaged").find("start_ut") != std::string::npos);
  CHECK(node.round().history().empty());
  Camera cam{rig};
  cam.run(2 * kS);
  cam.pile = true;
  cam.run(3 * kS);
  REQUIRE(node.round().state() == RoundState::kRunning);
  const nlohmann::json book = nlohmann::json::parse(harness::read_file(file));
  CHECK(book["running"]["max_score"] == 30);
}

TEST_CASE("the projection's configuration is checked before anything opens") {
  harness::Rig rig(kStepUs);
  ProjectionConfig c = quick_config("");
  c.window = true;  // and headless
  CHECK_THROWS_AS(rig.add<ProjectionNode>(c), std::invalid_argument);
  c = quick_config("");
  c.round_seconds = 0;
  CHECK_THROWS_AS(rig.add<ProjectionNode>(c), std::invalid_argument);
  c = quick_config("");
  c.display = "x";
  c.headless = false;
  CHECK_THROWS_AS(rig.add<ProjectionNode>(c), std::invalid_argument);
  c = quick_config("");
  c.snapshot_every = 2;
  CHECK_THROWS_AS(rig.add<ProjectionNode>(c), std::invalid_argument);
  c = quick_config("");
  c.state_width = 2000;
  CHECK_THROWS_AS(rig.add<ProjectionNode>(c), std::invalid_argument);
  c = quick_config("");
  c.condition = "green";
  CHECK_THROWS_AS(rig.add<ProjectionNode>(c), std::invalid_argument);
}

namespace {

void press(harness::Rig& rig, SDL_Keycode key) {
  SDL_Event e{};
  e.type = SDL_KEYDOWN;
  e.key.keysym.sym = key;
  REQUIRE(SDL_PushEvent(&e) == 1);
  rig.step();
}

void set_condition(harness::Rig& rig, int32_t index) {
  command_t c{};
  c.utime = rig.now();
  c.command = command_t::SET_CONDITION;
  c.index = index;
  rig.publish(channel(kCommandChannel), c);
}

// The newest projector image and the colour (BGR) at a board point, in its 256-pixel-wide state image.
cv::Vec3b drawn_at(harness::Recorder& rec, double x, double y) {
  const auto states = rec.all<projector_state_t>(channel(kProjectorChannel));
  REQUIRE_FALSE(states.empty());
  const cv::Mat image = cv::imdecode(states.back().image.data, cv::IMREAD_COLOR);
  REQUIRE(image.cols == 256);
  const board::Point2 p = board::BoardToProjector{}.map(x, y);
  return image.at<cv::Vec3b>(static_cast<int>(p.y / 4), static_cast<int>(p.x / 4));
}

bool red(const cv::Vec3b& px) { return px[2] > 150 && px[0] == 0 && px[1] == 0; }
bool blue(const cv::Vec3b& px) { return px[0] > 150 && px[2] == 0 && px[1] == 0; }

}  // namespace

TEST_CASE("on the rig the display condition comes from the flag, SET_CONDITION and key C, and every round_t carries it") {
  harness::Rig rig(kStepUs);
  ProjectionConfig config = quick_config("");
  config.condition = "blue";
  auto& node = rig.add<ProjectionNode>(config);
  auto& rec = rig.record({channel(kRoundChannel), channel(kProjectorChannel), channel(kHeartbeatChannel)});
  Camera cam{rig};
  cam.pile = true;
  cam.balanced = false;  // block 2 (row 1, x -0.7) is the cause, block 1 (row 0, x -0.8) stands on the surface
  auto bottom = [&rec] { return drawn_at(rec, -0.8 + 0.5, 0.5 / 3.0); };
  auto top = [&rec] { return drawn_at(rec, -0.7 + 0.5, 1.5 / 3.0); };
  cam.run(1 * kS);
  CHECK(node.condition() == DisplayCondition::kBlue);
  const auto rounds = rec.all<round_t>(channel(kRoundChannel));
  REQUIRE(rounds.size() >= 1);
  for (const round_t& r : rounds) CHECK(r.condition == study_session_t::CONDITION_BLUE);
  INFO("blue: the cause " << top() << ", the other " << bottom());
  CHECK(blue(top()));  // a falling pile, yet no red
  CHECK(blue(bottom()));
  const auto hb = rec.wait_for_heartbeat("projection", {}, 0ms);
  REQUIRE(hb);
  const auto named = std::find(hb->value_names.begin(), hb->value_names.end(), "condition");
  REQUIRE(named != hb->value_names.end());
  CHECK(hb->values[named - hb->value_names.begin()] == study_session_t::CONDITION_BLUE);

  // The study driver's command: red from the next round_t on, sent at once (not at the next second).
  rec.clear();
  const int64_t sent = rig.now();
  set_condition(rig, study_session_t::CONDITION_RED);
  cam.run(1 * kS);
  CHECK(node.condition() == DisplayCondition::kRed);
  const auto red_round = rec.wait_for<round_t>(channel(kRoundChannel), {}, 0ms);
  REQUIRE(red_round);
  CHECK(red_round->condition == study_session_t::CONDITION_RED);
  CHECK(red_round->utime <= sent + kStepUs);
  INFO("red: the cause " << top() << ", the other " << bottom());
  CHECK(red(top()));
  CHECK(red(bottom()));  // the whole pile while it falls

  // Bad indices: counted errors, the condition stays, the node goes on.
  const int64_t errors = node.counters().errors;
  for (int32_t bad : {0, 4, -3, 1 << 20}) set_condition(rig, bad);
  rec.clear();
  cam.run(1 * kS);
  CHECK(node.counters().errors == errors + 4);
  CHECK(node.condition() == DisplayCondition::kRed);
  const auto still = rec.all<round_t>(channel(kRoundChannel));
  REQUIRE_FALSE(still.empty());
  CHECK(still.back().condition == study_session_t::CONDITION_RED);

  // Key C: the next condition, proposed (only the cause red), then blue again.
  rec.clear();
  press(rig, SDLK_c);
  cam.run(1 * kS);
  CHECK(node.condition() == DisplayCondition::kProposed);
  CHECK(rec.all<round_t>(channel(kRoundChannel)).front().condition == study_session_t::CONDITION_PROPOSED);
  INFO("proposed: the cause " << top() << ", the other " << bottom());
  CHECK(red(top()));
  CHECK(blue(bottom()));
  press(rig, SDLK_c);
  CHECK(node.condition() == DisplayCondition::kBlue);

  // Under red the pile turns blue again once it stands.
  set_condition(rig, study_session_t::CONDITION_RED);
  cam.run(1 * kS);
  CHECK(red(bottom()));
  cam.balanced = true;
  cam.run(1 * kS);
  INFO("red, standing: the top " << top() << ", the bottom " << bottom());
  CHECK(blue(top()));
  CHECK(blue(bottom()));
}

TEST_CASE("on the rig a study session's instruction is shown while its driver is heard, and key D says done") {
  harness::Rig rig(kStepUs);
  ProjectionConfig config = quick_config("");
  config.stale_seconds = 0;  // an empty board without a camera: nothing else changes on the display
  auto& node = rig.add<ProjectionNode>(config);
  auto& rec = rig.record({channel(kProjectorChannel), channel(kStudyCommandChannel)});
  auto image = [&rec] {
    const auto states = rec.all<projector_state_t>(channel(kProjectorChannel));
    REQUIRE_FALSE(states.empty());
    return cv::imdecode(states.back().image.data, cv::IMREAD_COLOR);
  };
  rig.run_for(500ms);
  const cv::Mat before = image();
  CHECK(node.instruction().empty());

  study_session_t s{};
  s.session_id = "s07";
  s.subject_id = "p07";
  s.condition = study_session_t::CONDITION_RED;
  s.step = study_session_t::STEP_PROBLEM_1;
  s.state = study_session_t::STATE_RUNNING;
  s.instruction = "Add as few blocks as you can so that it stands. Say done when you are finished.";
  int64_t last_sent = 0;
  auto driver = [&](int seconds) {  // the driver's once-a-second state
    for (int k = 0; k < seconds; ++k) {
      s.utime = last_sent = rig.now();
      rig.publish(channel(kStudySessionChannel), s);
      rig.run_for(1s);
    }
  };
  driver(1);
  CHECK(node.instruction() == s.instruction);
  const cv::Mat shown = image();
  CHECK(cv::norm(before, shown, cv::NORM_L1) > 1000);  // the words are on the display
  cv::Mat green;
  cv::extractChannel(shown, green, 1);
  CHECK(cv::countNonZero(green) == 0);
  // Its condition is taken when first heard (a projection restarted mid-session shows the right one)...
  CHECK(node.condition() == DisplayCondition::kRed);
  // ...but not every second: a command wins until the session's condition changes.
  set_condition(rig, study_session_t::CONDITION_PROPOSED);
  driver(2);
  CHECK(node.condition() == DisplayCondition::kProposed);
  s.condition = study_session_t::CONDITION_BLUE;
  driver(1);
  CHECK(node.condition() == DisplayCondition::kBlue);

  // The subject says done at the board: DONE for this session, a new sequence each time.
  press(rig, SDLK_d);
  press(rig, SDLK_d);
  const auto done = rec.all<study_command_t>(channel(kStudyCommandChannel));
  REQUIRE(done.size() == 2);
  CHECK(done[0].command == study_command_t::DONE);
  CHECK(done[0].session_id == "s07");
  CHECK(done[1].sequence > done[0].sequence);

  // The driver gone quiet: the words go once three of its seconds are missed, not before.
  rig.run_until([&] { return node.instruction().empty(); }, 5s);
  CHECK(node.instruction().empty());
  CHECK(rig.now() == last_sent + ProjectionNode::kStudySessionHeardUs + kStepUs);  // the first step past 3 s
  rig.run_for(500ms);
  CHECK(cv::norm(before, image(), cv::NORM_L1) == 0);
  press(rig, SDLK_d);  // no session heard: for whichever session runs
  const auto any = rec.all<study_command_t>(channel(kStudyCommandChannel));
  REQUIRE(any.size() == 3);
  CHECK(any[2].session_id.empty());
}

namespace {
cv::Mat decode(const image_t& im) {
  return cv::imdecode(cv::Mat(1, static_cast<int>(im.data.size()), CV_8UC1, const_cast<uint8_t*>(im.data.data())),
                      cv::IMREAD_COLOR);
}
}  // namespace

TEST_CASE("on the rig the status page's projector JPEG comes every 2 s of the runtime clock, 320 px wide, in the projected colours") {
  harness::Rig rig(kStepUs);
  ProjectionConfig config = quick_config("");
  auto& rec = rig.record({channel(kProjectorImageChannel), channel(kProjectorChannel)});
  rig.add<ProjectionNode>(config);
  Camera camera{rig};
  camera.pile = true;
  camera.run(5 * kS);  // the game display with a pile of two blocks

  const auto game = rec.all<image_t>(channel(kProjectorImageChannel));
  // t = 0, 2 s, 4 s: exactly 2 s apart on the rig's clock (no wall clock could give exact steps).
  REQUIRE(game.size() == 3);
  for (size_t i = 1; i < game.size(); ++i) CHECK(game[i].utime - game[i - 1].utime == 2 * kS);
  for (const image_t& im : game) {
    CHECK(im.source == "projector");
    CHECK(im.format == image_t::FORMAT_JPEG);
    CHECK(im.width == 320);
    CHECK(im.height == 320 * config.height / config.width);
    const cv::Mat m = decode(im);
    REQUIRE(!m.empty());
    CHECK(m.cols == im.width);
    CHECK(m.rows == im.height);
  }
  // The last JPEG is the presented frame: against the projector state's lossless PNG of the same
  // moment, scaled to the same size, the colours differ only by JPEG's loss.
  const auto states = rec.all<projector_state_t>(channel(kProjectorChannel));
  REQUIRE(!states.empty());
  const cv::Mat jpeg = decode(game.back());
  cv::Mat state = decode(states.back().image), state_small;
  cv::resize(state, state_small, jpeg.size(), 0, 0, cv::INTER_AREA);
  cv::Mat diff;
  cv::absdiff(jpeg, state_small, diff);
  const cv::Scalar mean_diff = cv::mean(diff);
  INFO("mean colour difference " << mean_diff);
  CHECK(mean_diff[0] + mean_diff[1] + mean_diff[2] < 3 * 8.0);

  // A solid red pattern on the projector: the JPEG is red everywhere.
  command_t red{};
  red.command = command_t::SHOW_PATTERN;
  red.pattern = command_t::PATTERN_SOLID;
  red.red = 255;
  red.sequence = 1;
  rig.publish(channel(kCommandChannel), red);
  rig.run_for(2s);
  const auto all = rec.all<image_t>(channel(kProjectorImageChannel));
  REQUIRE(all.size() == 4);
  CHECK(all.back().utime - game.back().utime == 2 * kS);
  const cv::Mat shown = decode(all.back());
  REQUIRE(!shown.empty());
  for (const cv::Point p : {cv::Point(shown.cols / 2, shown.rows / 2), cv::Point(5, 5),
                            cv::Point(shown.cols - 5, shown.rows - 5)}) {
    const cv::Vec3b bgr = shown.at<cv::Vec3b>(p);
    INFO("pixel " << p << " = " << bgr);
    CHECK(bgr[2] > 230);
    CHECK(bgr[1] < 25);
    CHECK(bgr[0] < 25);
  }
}
