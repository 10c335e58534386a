// Screenshot tests with SDL's offscreen video driver: what the projector shows, read back with
// SDL_RenderReadPixels (Display::read_frame).
#include "bricklayer/projection/game_renderer.h"

#include <catch2/catch.hpp>

#include <cstdlib>
#include <filesystem>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "bricklayer/board/board_geometry.h"
#include "bricklayer/projection/display.h"
#include "bricklayer/projection/projection_node.h"

using namespace bricklayer;
using namespace bricklayer::projection;

namespace {

struct Fixture {
  Display display{DisplayOptions{DisplayMode::kHeadless, 0, 1024, 768, false, "test", ""}};
  GameRenderer renderer{display.renderer(), 1024, 768};

  cv::Mat draw(const Scene& scene, const board::BoardToProjector& mapping, const Hud& hud, int64_t anim_ms = 0) {
    display.begin_frame();
    renderer.draw_game(scene, mapping, hud, anim_ms);
    display.present();
    return display.read_frame();
  }
};

stack_t make_stack(int64_t frame, std::vector<std::tuple<int64_t, int, double>> blocks) {
  stack_t s{};
  s.frame_number = frame;
  s.block_length = 1;
  s.block_height = 1.0 / 3.0;
  s.status = stack_t::STATUS_OK;
  for (auto [id, row, x] : blocks) {
    block_t b{};
    b.id = id;
    b.row = row;
    b.x = x;
    s.blocks.push_back(b);
  }
  s.num_blocks = static_cast<int32_t>(s.blocks.size());
  return s;
}

prediction_t make_prediction(int64_t frame, std::vector<std::pair<int64_t, int8_t>> states) {
  prediction_t p{};
  p.frame_number = frame;
  p.status = prediction_t::STATUS_OK;
  for (auto [id, state] : states) {
    block_prediction_t b{};
    b.id = id;
    b.state = state;
    p.blocks.push_back(b);
  }
  p.num_blocks = static_cast<int32_t>(p.blocks.size());
  return p;
}

cv::Vec3b bgr(Rgb c) { return cv::Vec3b(c.b, 0, c.r); }

// Every pixel of a 7x7 grid inside the block (10% in from its edges) has the expected colour.
void check_block_colour(const cv::Mat& frame, const board::BoardToProjector& m, const SceneBlock& b, Rgb expected) {
  for (int i = 1; i <= 7; ++i) {
    for (int j = 1; j <= 7; ++j) {
      const double fx = 0.1 + 0.8 * (i - 1) / 6.0, fy = 0.1 + 0.8 * (j - 1) / 6.0;
      const board::Point2 p = m.map(b.x + fx, b.y + fy * b.height);
      const int u = static_cast<int>(std::lround(p.x)), v = static_cast<int>(std::lround(p.y));
      REQUIRE(u >= 0);
      REQUIRE(v >= 0);
      REQUIRE(u < frame.cols);
      REQUIRE(v < frame.rows);
      INFO("block " << b.id << " at projector (" << u << ", " << v << ")");
      CHECK(frame.at<cv::Vec3b>(v, u) == bgr(expected));
    }
  }
}

int green_pixels(const cv::Mat& frame) {
  cv::Mat green;
  cv::extractChannel(frame, green, 1);
  return cv::countNonZero(green);
}

int lit_pixels(const cv::Mat& frame, const SDL_Rect& r) {
  if (r.w <= 0 || r.h <= 0) return 0;
  cv::Mat grey;
  cv::cvtColor(frame(cv::Rect(r.x, r.y, r.w, r.h) & cv::Rect(0, 0, frame.cols, frame.rows)), grey, cv::COLOR_BGR2GRAY);
  return cv::countNonZero(grey);
}

void save_for_review(const cv::Mat& frame, const std::string& name) {
  const std::filesystem::path dir = std::filesystem::path(BRICKLAYER_BINARY_DIR) / "test-output" / "projection";
  std::filesystem::create_directories(dir);
  cv::imwrite((dir / name).string(), frame);
}

Hud hud_for(const Scene& scene) {
  Hud hud;
  hud.score = scene.score();
  hud.max_score = 87;
  hud.remaining_ms = 154000;
  hud.round_state = RoundState::kRunning;
  hud.num_blocks = static_cast<int>(scene.blocks().size());
  hud.overhang = scene.overhang();
  hud.best_overhang = 1.0;
  return hud;
}

}  // namespace

TEST_CASE("every block is filled with its predicted colour where the default mapping puts it") {
  Fixture f;
  Scene scene;
  scene.set_stack(make_stack(3, {{1, 0, -0.5}, {2, 1, 0.0}, {3, 2, 0.6}, {4, 0, -1.6}}));
  scene.set_prediction(make_prediction(3, {{1, block_prediction_t::STATE_STABLE},
                                          {2, block_prediction_t::STATE_MOVING},
                                          {3, block_prediction_t::STATE_CAUSE}}));
  board::BoardToProjector mapping;
  cv::Mat frame = f.draw(scene, mapping, hud_for(scene));
  save_for_review(frame, "blocks-default.png");
  REQUIRE(frame.size() == cv::Size(1024, 768));
  const auto& blocks = scene.blocks();
  check_block_colour(frame, mapping, blocks[0], kStableBlue);
  check_block_colour(frame, mapping, blocks[1], kMovingMagenta);
  check_block_colour(frame, mapping, blocks[2], kCauseRed);
  check_block_colour(frame, mapping, blocks[3], kUnknownDimBlue);  // no prediction for id 4
  // Between the blocks and outside them the board stays dark: right of block 3, left of the pile.
  const board::Point2 beyond = mapping.map(1.9, 5.0 / 6.0);
  CHECK(frame.at<cv::Vec3b>(static_cast<int>(beyond.y), static_cast<int>(beyond.x)) == cv::Vec3b(0, 0, 0));
  CHECK(green_pixels(frame) == 0);
}

TEST_CASE("a prediction for an older frame keeps its colours on the newest stack") {
  Fixture f;
  Scene scene;
  scene.set_stack(make_stack(10, {{1, 0, -0.5}, {2, 1, 0.0}}));
  scene.set_prediction(make_prediction(10, {{1, 0}, {2, 2}}));
  scene.set_stack(make_stack(11, {{1, 0, -0.5}, {2, 1, 0.05}, {3, 2, 0.3}}));
  board::BoardToProjector mapping;
  cv::Mat frame = f.draw(scene, mapping, hud_for(scene));
  check_block_colour(frame, mapping, scene.blocks()[0], kStableBlue);
  check_block_colour(frame, mapping, scene.blocks()[1], kCauseRed);
  check_block_colour(frame, mapping, scene.blocks()[2], kUnknownDimBlue);
}

TEST_CASE("blocks follow a calibrated mapping") {
  Fixture f;
  Scene scene;
  scene.set_stack(make_stack(1, {{1, 0, -0.5}, {2, 1, 0.2}}));
  scene.set_prediction(make_prediction(1, {{1, 2}, {2, 0}}));
  // A projector that is shifted, slightly scaled and keystoned relative to the camera.
  const std::array<double, 9> c2p = {1.5, 0.02, 40, -0.01, 1.45, 30, 1e-5, 2e-5, 1};
  board::BoardToProjector mapping = board::BoardToProjector::from_homographies(c2p, BoardGeometry{}.camera_to_board());
  cv::Mat frame = f.draw(scene, mapping, hud_for(scene));
  save_for_review(frame, "blocks-calibrated.png");
  check_block_colour(frame, mapping, scene.blocks()[0], kCauseRed);
  check_block_colour(frame, mapping, scene.blocks()[1], kStableBlue);
  // Where the default mapping would have put block 1 is not all red any more.
  board::BoardToProjector uncalibrated;
  const board::Point2 old = uncalibrated.map(-0.45, 0.03);
  CHECK(frame.at<cv::Vec3b>(static_cast<int>(old.y), static_cast<int>(old.x)) != bgr(kCauseRed));
}

TEST_CASE("score, MAX, closeness and timer are drawn as text, top right and top centre") {
  Fixture f;
  Scene scene;
  scene.set_stack(make_stack(1, {{1, 0, -0.25}, {2, 1, 0.1}}));
  scene.set_prediction(make_prediction(1, {{1, 0}, {2, 0}}));
  Hud hud = hud_for(scene);
  cv::Mat frame = f.draw(scene, board::BoardToProjector{}, hud);
  const Layout layout = f.renderer.layout();
  CHECK(lit_pixels(frame, layout.score) > 500);
  CHECK(lit_pixels(frame, layout.max) > 300);
  CHECK(lit_pixels(frame, layout.best) > 100);
  CHECK(lit_pixels(frame, layout.timer) > 500);
  // Top right: the score's right edge is near the right edge, in the top fifth of the image.
  CHECK(layout.score.x + layout.score.w > 1024 - 40);
  CHECK(layout.score.y < 768 / 5);
  CHECK(layout.max.y > layout.score.y);
  // Large enough to read across a room: the score text is at least 1/16 of the image high.
  CHECK(layout.score.h >= 768 / 16);
  CHECK(std::abs(layout.timer.x + layout.timer.w / 2 - 512) < 10);
  CHECK(green_pixels(frame) == 0);

  // No best-overhang table entry: that line is simply not drawn.
  hud.best_overhang.reset();
  cv::Mat without = f.draw(scene, board::BoardToProjector{}, hud);
  CHECK(f.renderer.layout().best.w == 0);
  CHECK(lit_pixels(without, layout.best) < lit_pixels(frame, layout.best));

  // A pile larger than the table: said plainly, on the same line.
  hud.best_known_up_to = hud.num_blocks - 1;
  cv::Mat beyond = f.draw(scene, board::BoardToProjector{}, hud);
  CHECK(f.renderer.layout().best.w > 0);
  CHECK(lit_pixels(beyond, f.renderer.layout().best) > 100);
  hud.best_known_up_to = hud.num_blocks;  // within the table but no entry: nothing
  f.draw(scene, board::BoardToProjector{}, hud);
  CHECK(f.renderer.layout().best.w == 0);
}

TEST_CASE("the miniature shows the pile with its colours, the collapse ghost and the hint, green stays 0") {
  Fixture f;
  Scene scene;
  scene.set_stack(make_stack(7, {{1, 0, -0.3}, {2, 1, 0.3}, {3, 2, 0.9}}));
  scene.set_prediction(make_prediction(7, {{1, 0}, {2, 1}, {3, 2}}));
  collapse_preview_t preview{};
  preview.frame_number = 7;
  preview.num_blocks = 3;
  preview.block_ids = {1, 2, 3};
  preview.end_state = {collapse_preview_t::END_UNTOUCHED, collapse_preview_t::END_AT_REST,
                       collapse_preview_t::END_FELL_OFF};
  preview.num_frames = 2;
  preview.time_s = {0.0, 0.4};
  preview.num_values = 18;
  preview.poses = {0.2, 1 / 6.0, 0, 0.8, 0.5, 0, 1.4, 5 / 6.0, 0,
                   0.2, 1 / 6.0, 0, 0.9, 0.3, -0.3, 1.6, 0.2, -0.9};
  scene.set_preview(preview);
  hint_t hint{};
  hint.num_blocks = 1;
  hint.rows = {1};
  hint.xs = {-0.7};
  scene.set_hint(hint);
  Hud hud = hud_for(scene);
  cv::Mat frame = f.draw(scene, board::BoardToProjector{}, hud, /*anim_ms=*/250);
  save_for_review(frame, "minimap.png");
  const SDL_Rect box = f.renderer.layout().minimap;
  REQUIRE(box.w > 100);
  cv::Mat mini = frame(cv::Rect(box.x, box.y, box.w, box.h));
  // All three state colours appear in the miniature, and so do the ghost's and hint's colours.
  auto count = [&](Rgb c) {
    cv::Mat mask;
    cv::inRange(mini, bgr(c), bgr(c), mask);
    return cv::countNonZero(mask);
  };
  CHECK(count(kStableBlue) > 50);  // block 1 (and the hint outline, also blue)
  CHECK(count(kMovingMagenta) > 50);
  CHECK(count(kCauseRed) > 50);
  CHECK(count(kGhost) > 20);
  CHECK(green_pixels(frame) == 0);
  // The animation moves: another time, another picture.
  cv::Mat later = f.draw(scene, board::BoardToProjector{}, hud, 1000);
  CHECK(cv::norm(frame, later, cv::NORM_L1) > 0);
  CHECK(green_pixels(later) == 0);
}

TEST_CASE("an ended round and an empty board also keep green at 0") {
  Fixture f;
  Scene scene;
  Hud hud;
  hud.round_state = RoundState::kEnded;
  hud.max_score = 123;
  cv::Mat frame = f.draw(scene, board::BoardToProjector{}, hud);
  CHECK(green_pixels(frame) == 0);
  CHECK(lit_pixels(frame, f.renderer.layout().round_label) > 50);  // "TIME UP"
}

TEST_CASE("a calibration pattern fills the whole projector image, green included") {
  Fixture f;
  command_t c{};
  c.command = command_t::SHOW_PATTERN;
  c.pattern = command_t::PATTERN_SOLID;
  c.red = 10;
  c.green = 200;
  c.blue = 30;
  f.display.begin_frame();
  f.renderer.draw_pattern(render_command_pattern(c, 1024, 768));
  f.display.present();
  cv::Mat frame = f.display.read_frame();
  cv::Mat mask;
  cv::inRange(frame, cv::Vec3b(30, 200, 10), cv::Vec3b(30, 200, 10), mask);
  CHECK(cv::countNonZero(mask) == 1024 * 768);
}

TEST_CASE("a Gray-code pattern is shown pixel for pixel") {
  Fixture f;
  command_t c{};
  c.command = command_t::SHOW_PATTERN;
  c.pattern = command_t::PATTERN_GRAY_CODE;
  c.index = 0;
  cv::Mat pattern;
  try {
    pattern = render_command_pattern(c, 1024, 768);
  } catch (const std::invalid_argument& e) {
    WARN("built without calibration patterns: " << e.what());
    return;
  }
  f.display.begin_frame();
  f.renderer.draw_pattern(pattern);
  f.display.present();
  cv::Mat frame = f.display.read_frame();
  CHECK(cv::norm(frame, pattern, cv::NORM_INF) == 0);
}

TEST_CASE("a stale input takes the verdict colours off the blocks and says so in the middle") {
  Fixture f;
  Scene scene;
  scene.set_stack(make_stack(3, {{1, 0, -0.5}, {2, 1, 0.3}}));
  scene.set_prediction(make_prediction(3, {{1, block_prediction_t::STATE_STABLE}, {2, block_prediction_t::STATE_CAUSE}}));
  board::BoardToProjector mapping;
  Hud hud = hud_for(scene);
  cv::Mat live = f.draw(scene, mapping, hud);
  check_block_colour(live, mapping, scene.blocks()[1], kCauseRed);
  CHECK(f.renderer.layout().notice.w == 0);
  for (const char* words : {"camera not seeing", "waiting for the other machine"}) {
    hud.notice = words;
    cv::Mat stale = f.draw(scene, mapping, hud);
    save_for_review(stale, std::string("stale-") + (words[0] == 'c' ? "camera" : "other") + ".png");
    INFO(words);
    check_block_colour(stale, mapping, scene.blocks()[0], kUnknownDimBlue);  // no frozen blue
    check_block_colour(stale, mapping, scene.blocks()[1], kUnknownDimBlue);  // no frozen red
    const SDL_Rect n = f.renderer.layout().notice;
    CHECK(lit_pixels(stale, n) > 500);
    CHECK(std::abs(n.x + n.w / 2 - 512) < 10);  // centred
    CHECK(std::abs(n.y + n.h / 2 - 384) < 60);
    CHECK(green_pixels(stale) == 0);
  }
}

TEST_CASE("between rounds the display shows how to start, the last MAX and the day's best") {
  Fixture f;
  Scene scene;
  Hud hud;
  hud.round_state = RoundState::kIdle;
  hud.rounds_today = 0;
  f.draw(scene, board::BoardToProjector{}, hud);
  CHECK(f.renderer.layout().day_best.w == 0);  // no round today: no line
  CHECK(round_label(hud) == "place a block on the board to start");
  hud.auto_start = false;
  CHECK(round_label(hud) == "press S to start");
  hud.auto_start = true;
  hud.round_state = RoundState::kEnded;
  hud.last_end = RoundEnd::kBoardCleared;
  hud.max_score = 140;
  hud.day_best = 230;
  hud.rounds_today = 3;
  CHECK(round_label(hud) == "ROUND OVER - clear the board to play again");
  hud.last_end = RoundEnd::kTimeUp;
  CHECK(round_label(hud) == "TIME UP - clear the board to play again");
  cv::Mat frame = f.draw(scene, board::BoardToProjector{}, hud);
  save_for_review(frame, "between-rounds.png");
  const Layout layout = f.renderer.layout();
  CHECK(lit_pixels(frame, layout.day_best) > 200);
  CHECK(lit_pixels(frame, layout.max) > 200);
  CHECK(lit_pixels(frame, layout.round_label) > 200);
  CHECK(layout.day_best.y > layout.max.y);
  CHECK(layout.day_best.x + layout.day_best.w > 1024 - 40);
  CHECK(green_pixels(frame) == 0);
}

TEST_CASE("a knife edge: the deciding block blue inside with a red outline, the margin text under the miniature") {
  Fixture f;
  Scene scene;
  scene.set_stack(make_stack(5, {{1, 0, -0.6}, {2, 1, -0.1}}));
  prediction_t p = make_prediction(5, {{1, block_prediction_t::STATE_STABLE}, {2, block_prediction_t::STATE_STABLE}});
  p.verdict = prediction_t::VERDICT_KNIFE_EDGE;
  p.raw_verdict = prediction_t::VERDICT_KNIFE_EDGE;
  p.margin = -0.004;
  p.margin_mm = -0.3;
  p.uncertainty = 0.003;
  p.blocks[1].deciding = true;
  scene.set_prediction(p);
  board::BoardToProjector mapping;
  const cv::Mat frame = f.draw(scene, mapping, hud_for(scene), 800);  // the pulse at its brightest
  save_for_review(frame, "knife-edge.png");
  const auto& blocks = scene.blocks();
  check_block_colour(frame, mapping, blocks[0], kStableBlue);  // not deciding: plain blue
  check_block_colour(frame, mapping, blocks[1], kStableBlue);  // deciding: still blue inside
  // On the deciding block's bottom edge, a pixel inwards: lit red (the outline), not the blue fill.
  const board::Point2 edge = mapping.map(blocks[1].x + 0.5, blocks[1].y);
  bool red = false;
  for (int dv = -3; dv <= 3 && !red; ++dv) {
    const cv::Vec3b px = frame.at<cv::Vec3b>(static_cast<int>(std::lround(edge.y)) + dv, static_cast<int>(std::lround(edge.x)));
    red = px[2] > 200;
  }
  CHECK(red);
  CHECK(green_pixels(frame) == 0);
  CHECK(lit_pixels(frame, f.renderer.layout().margin) > 0);
  CHECK(f.renderer.layout().margin.y > f.renderer.layout().minimap.y);

  // A certain verdict: no outline; a prediction judged without uncertainty: no text.
  p.verdict = prediction_t::VERDICT_STABLE;
  p.uncertainty = 0.0;
  scene.set_prediction(p);
  const cv::Mat plain = f.draw(scene, mapping, hud_for(scene), 800);
  CHECK(f.renderer.layout().margin.w == 0);
  const cv::Vec3b px = plain.at<cv::Vec3b>(static_cast<int>(std::lround(edge.y)) - 2, static_cast<int>(std::lround(edge.x)));
  CHECK(px[2] == 0);
}

namespace {

// Pixels lit red with no blue at all: only a red block (or outline) is drawn so; text and ghosts mix both.
int pure_red_pixels(const cv::Mat& frame) {
  cv::Mat mask;
  cv::inRange(frame, cv::Vec3b(0, 0, 1), cv::Vec3b(0, 0, 255), mask);
  return cv::countNonZero(mask);
}

int count_colour(const cv::Mat& image, Rgb c) {
  cv::Mat mask;
  cv::inRange(image, bgr(c), bgr(c), mask);
  return cv::countNonZero(mask);
}

collapse_preview_t falling_preview(int64_t frame) {
  collapse_preview_t preview{};
  preview.frame_number = frame;
  preview.num_blocks = 3;
  preview.block_ids = {1, 2, 3};
  preview.end_state = {collapse_preview_t::END_UNTOUCHED, collapse_preview_t::END_AT_REST,
                       collapse_preview_t::END_FELL_OFF};
  preview.num_frames = 2;
  preview.time_s = {0.0, 0.4};
  preview.num_values = 18;
  preview.poses = {0.2, 1 / 6.0, 0, 0.8, 0.5, 0, 1.4, 5 / 6.0, 0,
                   0.2, 1 / 6.0, 0, 0.9, 0.3, -0.3, 1.6, 0.2, -0.9};
  return preview;
}

}  // namespace

TEST_CASE("each display condition lights a falling pile as the study says, on the board and in the miniature") {
  Fixture f;
  Scene scene;
  scene.set_stack(make_stack(7, {{1, 0, -0.3}, {2, 1, 0.3}, {3, 2, 0.9}}));
  scene.set_prediction(make_prediction(7, {{1, block_prediction_t::STATE_STABLE},
                                          {2, block_prediction_t::STATE_MOVING},
                                          {3, block_prediction_t::STATE_CAUSE}}));
  scene.set_preview(falling_preview(7));
  board::BoardToProjector mapping;
  const auto& blocks = scene.blocks();
  struct Expect {
    DisplayCondition condition;
    Rgb fill[3];
    bool ghost;
  };
  for (const Expect& e : {Expect{DisplayCondition::kBlue, {kStableBlue, kStableBlue, kStableBlue}, false},
                          Expect{DisplayCondition::kRed, {kCauseRed, kCauseRed, kCauseRed}, false},
                          Expect{DisplayCondition::kProposed, {kStableBlue, kMovingMagenta, kCauseRed}, true}}) {
    INFO("condition " << condition_name(e.condition));
    Hud hud = hud_for(scene);
    hud.condition = e.condition;
    const cv::Mat frame = f.draw(scene, mapping, hud, 250);
    save_for_review(frame, std::string("condition-") + condition_name(e.condition) + "-falling.png");
    for (int k = 0; k < 3; ++k) check_block_colour(frame, mapping, blocks[k], e.fill[k]);
    const SDL_Rect box = f.renderer.layout().minimap;
    const cv::Mat mini = frame(cv::Rect(box.x, box.y, box.w, box.h));
    // The miniature tells the same: its blocks in the same colours, the ghost only under proposed.
    CHECK((count_colour(mini, kCauseRed) > 50) == (e.condition != DisplayCondition::kBlue));
    CHECK((count_colour(mini, kStableBlue) > 50) == (e.condition != DisplayCondition::kRed));
    CHECK((count_colour(mini, kMovingMagenta) > 50) == (e.condition == DisplayCondition::kProposed));
    CHECK((count_colour(mini, kGhost) > 20) == e.ghost);
    if (e.condition == DisplayCondition::kBlue) CHECK(pure_red_pixels(frame) == 0);  // no red anywhere
    CHECK(green_pixels(frame) == 0);
  }
}

TEST_CASE("a standing pile is all blue under every display condition") {
  Fixture f;
  Scene scene;
  scene.set_stack(make_stack(8, {{1, 0, -0.6}, {2, 1, -0.3}, {3, 2, -0.1}}));
  scene.set_prediction(make_prediction(8, {{1, block_prediction_t::STATE_STABLE},
                                          {2, block_prediction_t::STATE_STABLE},
                                          {3, block_prediction_t::STATE_STABLE}}));
  board::BoardToProjector mapping;
  for (auto c : {DisplayCondition::kBlue, DisplayCondition::kRed, DisplayCondition::kProposed}) {
    INFO("condition " << condition_name(c));
    Hud hud = hud_for(scene);
    hud.condition = c;
    const cv::Mat frame = f.draw(scene, mapping, hud);
    save_for_review(frame, std::string("condition-") + condition_name(c) + "-standing.png");
    for (const SceneBlock& b : scene.blocks()) check_block_colour(frame, mapping, b, kStableBlue);
    CHECK(pure_red_pixels(frame) == 0);
    CHECK(green_pixels(frame) == 0);
  }
}

TEST_CASE("a knife edge under red and blue: all blue, no outline, no margin text") {
  Fixture f;
  Scene scene;
  scene.set_stack(make_stack(5, {{1, 0, -0.6}, {2, 1, -0.1}}));
  prediction_t p = make_prediction(5, {{1, block_prediction_t::STATE_STABLE}, {2, block_prediction_t::STATE_STABLE}});
  p.verdict = prediction_t::VERDICT_KNIFE_EDGE;
  p.raw_verdict = prediction_t::VERDICT_KNIFE_EDGE;
  p.margin = -0.004;
  p.margin_mm = -0.3;
  p.uncertainty = 0.003;
  p.blocks[1].deciding = true;
  scene.set_prediction(p);
  board::BoardToProjector mapping;
  for (auto c : {DisplayCondition::kBlue, DisplayCondition::kRed, DisplayCondition::kProposed}) {
    INFO("condition " << condition_name(c));
    Hud hud = hud_for(scene);
    hud.condition = c;
    const cv::Mat frame = f.draw(scene, mapping, hud, 800);  // the pulse at its brightest
    for (const SceneBlock& b : scene.blocks()) check_block_colour(frame, mapping, b, kStableBlue);
    const bool proposed = c == DisplayCondition::kProposed;
    CHECK((pure_red_pixels(frame) > 0) == proposed);  // the outline
    CHECK((f.renderer.layout().margin.w > 0) == proposed);
    CHECK(green_pixels(frame) == 0);
  }
}

TEST_CASE("a study session's instruction is drawn wrapped below the top's texts, covering none of them") {
  Fixture f;
  Scene scene;
  scene.set_stack(make_stack(2, {{1, 0, -0.5}}));
  prediction_t p = make_prediction(2, {{1, block_prediction_t::STATE_STABLE}});
  p.uncertainty = 0.003;  // judged with an uncertainty: the margin line under the miniature is drawn
  p.margin_mm = 2.0;
  scene.set_prediction(p);
  board::BoardToProjector mapping;
  Hud hud = hud_for(scene);
  hud.day_best = 230;
  hud.rounds_today = 3;  // the score column at its longest
  const cv::Mat without = f.draw(scene, mapping, hud);
  CHECK(f.renderer.layout().instruction.w == 0);
  hud.instruction =
      "Build the pile shown by the outlines. It falls. Add as few blocks as you can so that it stands, without "
      "moving the blocks shown. Say done when you are finished.";
  const cv::Mat with = f.draw(scene, mapping, hud);
  save_for_review(with, "instruction.png");
  const Layout layout = f.renderer.layout();
  const SDL_Rect r = layout.instruction;
  CHECK(lit_pixels(with, r) > 2000);
  CHECK(lit_pixels(without, r) < lit_pixels(with, r));
  // Wrapped into several lines of the small font ("SCORE" is one such line), none wider than 60 % of the image.
  REQUIRE(layout.score_label.h > 0);
  CHECK(r.h >= 3 * layout.score_label.h);
  CHECK(r.w <= 1024 * 60 / 100);
  CHECK(std::abs(r.x + r.w / 2 - 512) < 10);
  REQUIRE(layout.margin.w > 0);
  REQUIRE(layout.day_best.w > 0);
  int k = 0;
  for (const SDL_Rect& other : {layout.minimap, layout.margin, layout.timer, layout.score, layout.score_label, layout.max,
                                layout.best, layout.day_best}) {
    INFO("layout rectangle " << k++);
    CHECK_FALSE(SDL_HasIntersection(&r, &other));
  }
  const board::Point2 block_top = mapping.map(-0.5, 1.0 / 3.0);
  CHECK(r.y + r.h < block_top.y);  // above the pile
  check_block_colour(with, mapping, scene.blocks()[0], kStableBlue);  // the pile is still drawn
  CHECK(green_pixels(with) == 0);
}
