#include "bricklayer/projection/projection_node.h"

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <stdexcept>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "bricklayer/common/channels.h"
#include "bricklayer/common/log.h"
#include "bricklayer/messages/timing.h"
#include "bricklayer/patterns/patterns.h"
#include "bricklayer/projection/round_book.h"
#include "bricklayer/projector_state_t.hpp"
#include "bricklayer/round_t.hpp"
#include "bricklayer/study_command_t.hpp"

#ifndef BRICKLAYER_DEFAULT_BEST_OVERHANG
#define BRICKLAYER_DEFAULT_BEST_OVERHANG ""
#endif

namespace bricklayer::projection {

std::string default_best_overhang_path() { return BRICKLAYER_DEFAULT_BEST_OVERHANG; }

cv::Mat render_command_pattern(const command_t& command, int width, int height) {
  return patterns::render_pattern(command, cv::Size(width, height));
}

namespace {

bool write_png_atomically(const std::filesystem::path& path, const cv::Mat& bgr) {
  std::vector<uint8_t> png;
  if (!cv::imencode(".png", bgr, png)) return false;
  const std::filesystem::path tmp = path.string() + ".tmp";
  FILE* f = std::fopen(tmp.c_str(), "wb");
  if (!f) return false;
  const bool ok = std::fwrite(png.data(), 1, png.size(), f) == png.size();
  if (std::fclose(f) != 0 || !ok) return false;
  std::error_code ec;
  std::filesystem::rename(tmp, path, ec);
  return !ec;
}

DisplayOptions display_options(const ProjectionConfig& c) {
  DisplayOptions d;
  if (c.headless) {
    d.mode = DisplayMode::kHeadless;
  } else if (c.window) {
    d.mode = DisplayMode::kWindow;
  } else {
    d.mode = DisplayMode::kFullscreen;
    d.display_index = c.display.empty() ? 0 : std::stoi(c.display);
  }
  d.width = c.width;
  d.height = c.height;
  d.vsync = !c.no_vsync;
  d.render_driver = c.renderer;
  return d;
}

RoundRules round_rules(const ProjectionConfig& c) {
  RoundRules r;
  r.duration_us = static_cast<int64_t>(c.round_seconds * 1e6);
  r.start_hold_us = static_cast<int64_t>(c.round_start_hold * 1e6);
  r.arm_empty_us = static_cast<int64_t>(c.round_arm_empty * 1e6);
  r.end_empty_us = static_cast<int64_t>(c.round_end_empty * 1e6);
  r.auto_start = !c.no_auto_start;
  return r;
}

const ProjectionConfig& checked(const ProjectionConfig& c) {
  runtime::validate(c);
  ProjectionNode::check(c);
  return c;
}

// A new stack is drawn together with its prediction. Drawing it alone (its colours still unknown) would
// spend a whole draw just before the prediction arrives (a fraction of a millisecond later) and delay the
// frame that matters by that draw. So while predictions are flowing, a new stack waits for its own
// prediction up to kPredictionHoldUs; without a prediction process it is drawn at once.
constexpr int64_t kPredictionHoldUs = 15'000;
constexpr int64_t kPredictionsFlowingUs = 2'000'000;

// A problem and the session it belongs to go silent under the same rule.
static_assert(ProblemOutline::kHeardUs == ProjectionNode::kStudySessionHeardUs);

}  // namespace

void ProjectionNode::check(const Config& c) {
  const int modes = (c.display.empty() ? 0 : 1) + (c.window ? 1 : 0) + (c.headless ? 1 : 0);
  if (modes > 1) throw std::invalid_argument("choose one of --display i, --window and --headless");
  if (c.state_width > c.width) throw std::invalid_argument("--state-width must be in 16.." + std::to_string(c.width));
  if (c.snapshot_every > 0 && c.snapshot_dir.empty()) throw std::invalid_argument("--snapshot-every needs --snapshot-dir");
}

ProjectionNode::ProjectionNode(const Config& config, runtime::Bus& bus)
    : Node("projection", bus),
      config_(checked(config)),
      stack_channel_(channel(kStackChannel)),
      prediction_channel_(channel(kPredictionChannel)),
      command_channel_(channel(kCommandChannel)),
      round_channel_(channel(kRoundChannel)),
      projector_channel_(channel(kProjectorChannel)),
      timing_channel_(channel(kTimingChannel)),
      study_command_channel_(channel(kStudyCommandChannel)),
      round_(round_rules(config)),
      watch_(now(), static_cast<int64_t>(config.stale_seconds * 1e6)),
      debounce_(300, 1000),
      start_utime_(now()) {
  if (!config.snapshot_dir.empty()) {
    std::error_code ec;
    std::filesystem::create_directories(config.snapshot_dir, ec);
    if (ec || !std::filesystem::is_directory(config.snapshot_dir))
      throw std::runtime_error("cannot create the snapshot folder '" + config.snapshot_dir + "': " + ec.message());
  }
  if (!config.best_overhang.empty()) {
    try {
      best_overhang_ = BestOverhang::load(config.best_overhang);
    } catch (const std::exception& e) {
      log::warn(e.what(), "; the best-overhang line is not shown");
    }
  }
  restore_rounds();
  // runtime::validate has checked the name against the same three.
  condition_ = condition_from_name(config.condition).value_or(DisplayCondition::kProposed);

  display_ = std::make_unique<Display>(display_options(config));
  renderer_ = std::make_unique<GameRenderer>(display_->renderer(), config.width, config.height, config.font);
  if (!config.mute) beeper_ = std::make_unique<Beeper>(ToneOptions{});

  using runtime::QueuePolicy;
  subscribe<stack_t>(stack_channel_, QueuePolicy::newest(), [this](const stack_t& s) { on_stack(s); });
  subscribe<prediction_t>(prediction_channel_, QueuePolicy::newest(), [this](const prediction_t& p) { on_prediction(p); });
  subscribe<calibration_t>(channel(kCalibrationChannel), QueuePolicy::newest(),
                           [this](const calibration_t& c) { on_calibration(c); });
  subscribe<hint_t>(channel(kHintChannel), QueuePolicy::newest(), [this](const hint_t& h) {
    try {
      scene_.set_hint(h);
      dirty_ = true;
    } catch (const std::exception& e) {
      error("rejected hints", std::string("hint rejected: ") + e.what());
    }
  });
  subscribe<collapse_preview_t>(channel(kPreviewChannel), QueuePolicy::newest(), [this](const collapse_preview_t& p) {
    try {
      scene_.set_preview(p);
      dirty_ = true;
    } catch (const std::exception& e) {
      error("rejected previews", std::string("collapse preview rejected: ") + e.what());
    }
  });
  subscribe<study_session_t>(channel(kStudySessionChannel), QueuePolicy::newest(),
                             [this](const study_session_t& s) { on_study_session(s); });
  subscribe<study_problem_t>(channel(kStudyProblemChannel), QueuePolicy::newest(),
                             [this](const study_problem_t& p) { on_study_problem(p); });
  // Every command counts (no newest-wins); a flood keeps the newest thousand.
  subscribe<command_t>(command_channel_, QueuePolicy::keep(1000), [this](const command_t& c) { apply_command(c); });

  set_tick_ms(std::max(1, 1000 / config.fps));
  next_snapshot_utime_ = config.snapshot_every > 0 ? now() : INT64_MAX;
  next_status_image_utime_ = config.status_image_every > 0 ? now() : INT64_MAX;
}

ProjectionNode::~ProjectionNode() = default;

void ProjectionNode::restore_rounds() {
  if (config_.rounds_file.empty()) return;
  // A fresh install has no logs/ yet: the book's folder is made here, or the start fails saying why.
  const std::filesystem::path folder = std::filesystem::path(config_.rounds_file).parent_path();
  std::error_code ec;
  if (!folder.empty()) std::filesystem::create_directories(folder, ec);
  if (ec || (!folder.empty() && !std::filesystem::is_directory(folder)))
    throw std::runtime_error("cannot create the round book's folder '" + folder.string() + "': " + ec.message());
  RoundBook book;
  try {
    book = load_round_book(config_.rounds_file);
  } catch (const std::exception& e) {
    // Kept aside for a person to look at; the exhibit goes on with a fresh book.
    const std::string aside = config_.rounds_file + ".damaged";
    ec.clear();
    std::filesystem::rename(config_.rounds_file, aside, ec);
    error("damaged round books", std::string(e.what()) + "; kept as " + aside + ", starting a new round book");
  }
  const size_t rounds = book.history.size();
  const bool running = book.running.has_value();
  round_.restore(std::move(book.history), book.running, now());
  saved_revision_ = round_.revision();
  if (rounds > 0 || running)
    log::info("round book ", config_.rounds_file, ": ", rounds, " round(s)", running ? ", one running" : "",
              "; today's best ", round_.day_best(now()));
  if (running && round_.state() != RoundState::kRunning) save_rounds();  // closed while we were down
}

void ProjectionNode::save_rounds() {
  saved_revision_ = round_.revision();  // tried: the next change tries again, no retry storm
  if (config_.rounds_file.empty()) return;
  try {
    save_round_book(config_.rounds_file, RoundBook{round_.history(), round_.running()});
  } catch (const std::exception& e) {
    error("failed round book saves", e.what());
  }
}

bool ProjectionNode::awaiting_prediction() const {
  const int64_t t = now();
  return stack_arrived_utime_ >= 0 && t - stack_arrived_utime_ < kPredictionHoldUs &&
         last_prediction_utime_ != INT64_MIN && t - last_prediction_utime_ < kPredictionsFlowingUs && !pattern_ &&
         scene_.prediction_for_stack() == nullptr;
}

void ProjectionNode::on_stack(const stack_t& s) {
  try {
    const int rejected = scene_.set_stack(s);
    if (rejected > 0) {
      for (int k = 0; k < rejected; ++k)
        error("rejected blocks", std::to_string(rejected) + " block(s) of frame " + std::to_string(s.frame_number) +
                                     " rejected (non-finite x or bad row)");
    }
  } catch (const std::exception& e) {
    error("rejected stacks", std::string("stack rejected: ") + e.what());
    return;
  }
  dirty_ = true;
  stack_arrived_utime_ = now();
  if (awaiting_prediction()) wake_at(stack_arrived_utime_ + kPredictionHoldUs);
  // Only a measurement says what is on the board: a frame that could not be read or a covered board
  // is neither empty nor a pile, and counts as the camera not seeing.
  if (s.status == stack_t::STATUS_OK) {
    watch_.stack_seen(now());
    round_.board_seen(now(), static_cast<int>(scene_.blocks().size()));
  }
}

void ProjectionNode::on_prediction(const prediction_t& p) {
  try {
    scene_.set_prediction(p);
  } catch (const std::exception& e) {
    error("rejected predictions", std::string("prediction rejected: ") + e.what());
    return;
  }
  last_prediction_utime_ = now();
  watch_.prediction_seen(now());
  prediction_received_ = std::chrono::steady_clock::now();
  prediction_received_utime_ = now();
  dirty_ = true;
}

void ProjectionNode::on_calibration(const calibration_t& c) {
  // bricklayer-calibrate --serve republishes the calibration every second: an unchanged one is not
  // applied (nor logged) again.
  if (applied_calibration_ && runtime::encode(*applied_calibration_) == runtime::encode(c)) return;
  applied_calibration_ = c;
  try {
    board::BoardToProjector mapping = board::BoardToProjector::from_calibration(c);
    if (c.projector_width > 0 && c.projector_height > 0 &&
        (c.projector_width != display_->width() || c.projector_height != display_->height())) {
      // The same projector at another resolution: scale its pixels to ours.
      const double sx = static_cast<double>(display_->width()) / c.projector_width;
      const double sy = static_cast<double>(display_->height()) / c.projector_height;
      std::array<double, 9> c2p{};
      for (int k = 0; k < 9; ++k) c2p[k] = c.camera_to_projector[k];
      std::array<double, 9> c2b{};
      for (int k = 0; k < 9; ++k) c2b[k] = c.camera_to_board[k];
      mapping = board::BoardToProjector::from_homographies(board::multiply3({sx, 0, 0, 0, sy, 0, 0, 0, 1}, c2p), c2b);
      log::warn("calibration is for a ", c.projector_width, "x", c.projector_height, " projector; scaled to ",
                display_->width(), "x", display_->height());
    }
    mapping_ = mapping;
    dirty_ = true;
    log::info("calibration applied (reprojection error mean ", c.reprojection_error_mean_px, " px)");
  } catch (const std::exception& e) {
    error("rejected calibrations", std::string("calibration rejected: ") + e.what());
  }
}

void ProjectionNode::set_condition(DisplayCondition condition, const std::string& by) {
  if (condition == condition_) return;
  log::info("display condition ", condition_name(condition), " (was ", condition_name(condition_), "; ", by, ")");
  condition_ = condition;
  dirty_ = true;
  next_round_publish_utime_ = now();  // the next round_t says so at once
}

void ProjectionNode::on_study_session(const study_session_t& s) {
  study_session_ = s;
  study_session_utime_ = now();
  // The driver sends SET_CONDITION only before its games, so a projection restarted mid-session would
  // show the default to the subject: a session's condition is taken when first heard and when it changes
  // (not every second, so key C or a command still wins until the session's condition changes).
  if (auto c = condition_from_index(s.condition); c && study_condition_ != s.condition) {
    study_condition_ = s.condition;
    set_condition(*c, "study session " + s.session_id);
  }
}

const study_session_t* ProjectionNode::heard_session() const {
  if (!study_session_ || now() - study_session_utime_ > kStudySessionHeardUs) return nullptr;
  return &*study_session_;
}

std::string ProjectionNode::instruction() const {
  const study_session_t* s = heard_session();
  return s ? s->instruction : "";
}

void ProjectionNode::on_study_problem(const study_problem_t& p) {
  const std::string fault = study_problem_.take(p, now());
  if (!fault.empty()) {
    ++problems_rejected_;
    error("rejected study problems", "study problem " + std::to_string(p.problem) + " '" + p.name +
                                         "' not drawn: " + fault);
  }
}

ProblemView ProjectionNode::problem_view() const {
  return study_problem_.view(now(), heard_session(), study_session_utime_);
}

void ProjectionNode::send_done() {
  study_command_t c{};
  c.utime = now();
  // The session heard (if any); "" = whichever session is running.
  if (study_session_ && now() - study_session_utime_ <= kStudySessionHeardUs) c.session_id = study_session_->session_id;
  c.command = study_command_t::DONE;
  // Unique across senders, as bricklayer-study send does (the driver ignores a repeat of one sequence).
  study_command_sequence_ = std::max(study_command_sequence_ + 1, c.utime);
  c.sequence = study_command_sequence_;
  publish(study_command_channel_, c);
  log::info("study: done (key D)");
}

void ProjectionNode::apply_command(const command_t& c) {
  switch (c.command) {
    case command_t::START_ROUND: round_.start(now()); dirty_ = true; break;
    case command_t::RESET_ROUND: round_.reset(now()); dirty_ = true; break;
    case command_t::SHOW_PATTERN:
      try {
        pattern_ = render_command_pattern(c, display_->width(), display_->height());
        pattern_sequence_ = c.sequence;
        dirty_ = true;
      } catch (const std::exception& e) {
        error("patterns that cannot be shown",
              "cannot show pattern " + std::to_string(c.pattern) + " index " + std::to_string(c.index) + ": " + e.what());
      }
      break;
    case command_t::CLEAR_PATTERN:
      pattern_.reset();
      pattern_sequence_ = c.sequence;
      dirty_ = true;
      break;
    case command_t::CLEAR_HINT: scene_.clear_hint(); dirty_ = true; break;
    case command_t::SNAPSHOT: snapshot_requested_ = true; break;
    case command_t::SET_CONDITION:
      if (const auto condition = condition_from_index(c.index)) {
        set_condition(*condition, "command SET_CONDITION");
      } else {
        error("bad display conditions", "SET_CONDITION index " + std::to_string(c.index) +
                                            " is not 1 (blue), 2 (red) or 3 (proposed); the condition stays " +
                                            condition_name(condition_));
      }
      break;
    default: break;  // REQUEST_HINT, SELF_CHECK, ...: for other modules
  }
}

void ProjectionNode::handle_events() {
  SDL_Event event;
  while (SDL_PollEvent(&event)) {
    if (event.type == SDL_QUIT) quit_ = true;
    if (event.type == SDL_WINDOWEVENT) dirty_ = true;
    if (event.type != SDL_KEYDOWN || event.key.repeat) continue;
    switch (event.key.keysym.sym) {
      case SDLK_ESCAPE:
      case SDLK_q: quit_ = true; break;
      case SDLK_s: round_.start(now()); dirty_ = true; break;
      case SDLK_r: round_.reset(now()); dirty_ = true; break;
      case SDLK_h: request_hint(); break;
      case SDLK_c: set_condition(next_condition(condition_), "key C"); break;
      case SDLK_d: send_done(); break;
      case SDLK_p: snapshot_requested_ = true; break;
      default: break;
    }
  }
  if (quit_) stop();
}

void ProjectionNode::request_hint() {
  command_t c{};
  c.utime = now();
  c.command = command_t::REQUEST_HINT;
  c.sequence = ++hint_sequence_;
  publish(command_channel_, c);
}

void ProjectionNode::tick() {
  handle_events();
  advance_round();
  // A new instruction, or none once the driver has gone quiet.
  if (instruction() != drawn_instruction_) dirty_ = true;
  // A problem shown or gone, or its time left down a second.
  if (problem_view() != drawn_problem_) dirty_ = true;
  // The ghost moves only where it is drawn (proposed).
  const bool animating = !pattern_ && condition_ == DisplayCondition::kProposed && scene_.preview_for_stack() != nullptr;
  const bool refresh = display_->mode() != DisplayMode::kHeadless;  // a real screen redraws every refresh
  if ((dirty_ || animating || refresh) && !awaiting_prediction()) draw_and_present();
  capture_if_due();
}

void ProjectionNode::advance_round() {
  const int64_t t = now();
  const InputProblem problem = watch_.problem(t);
  if (problem != shown_problem_) {
    shown_problem_ = problem;
    dirty_ = true;
    if (problem == InputProblem::kNone) log::info("inputs are back");
    else log::warn(watch_.status(t));
  }
  const prediction_t* p = scene_.prediction_for_stack();
  const bool balanced = p && p->status == prediction_t::STATUS_OK && p->balanced;
  // A stale verdict scores nothing: MAX takes only what is live.
  round_.pile(t, scene_.score(), balanced && problem == InputProblem::kNone, static_cast<int>(scene_.blocks().size()));
  const bool round_changed = round_.update(t);
  if (round_changed) dirty_ = true;
  if (round_.revision() != saved_revision_) save_rounds();
  if (round_changed || t >= next_round_publish_utime_) {
    publish_round();
    next_round_publish_utime_ = t + 1'000'000;
  }
  // The beep follows what is shown: never under the blue condition.
  const bool alarm = pile_look(condition_, scene_, problem != InputProblem::kNone).alarm;
  if (debounce_.update(!pattern_ && alarm, t / 1000) && beeper_)
    beeper_->beep();
}

void ProjectionNode::before_heartbeat() {
  const int64_t t = now();
  if (!latencies_us_.empty()) {
    std::vector<int64_t> recent(latencies_us_.end() - std::min<size_t>(latencies_us_.size(), 200), latencies_us_.end());
    std::nth_element(recent.begin(), recent.begin() + recent.size() / 2, recent.end());
    set_value("present_p50_ms", recent[recent.size() / 2] / 1000.0);
  }
  set_value("frames", static_cast<double>(frames_presented_));
  set_value("calibrated", mapping_.calibrated() ? 1 : 0);
  set_value("day_best", round_.day_best(t));
  set_value("rounds_today", round_.rounds_today(t));
  set_value("condition", static_cast<int>(condition_));
  const std::string stale = watch_.status(t);
  set_status(pattern_ ? "pattern" : stale.empty() ? "ok" : stale);
}

void ProjectionNode::publish_round() {
  round_t r{};
  r.utime = now();
  r.state = static_cast<int8_t>(round_.state());
  r.duration_ms = round_.duration_ms();
  r.remaining_ms = round_.remaining_ms(r.utime);
  r.score = round_.score();
  r.max_score = round_.max_score();
  r.num_blocks = static_cast<int32_t>(scene_.blocks().size());
  r.best_possible = best_overhang_.best_for(r.num_blocks).value_or(0.0);
  r.condition = static_cast<int8_t>(condition_);
  publish(round_channel_, r);
}

void ProjectionNode::draw_and_present() {
  drawn_instruction_ = instruction();
  drawn_problem_ = problem_view();
  display_->begin_frame();
  if (pattern_) {
    renderer_->draw_pattern(*pattern_);
  } else {
    const int64_t t = now();
    Hud hud;
    hud.score = round_.score();
    hud.max_score = round_.max_score();
    hud.remaining_ms = round_.remaining_ms(t);
    hud.round_state = round_.state();
    if (const RoundRecord* last = round_.last_round()) hud.last_end = last->end;
    hud.auto_start = round_.rules().auto_start;
    hud.day_best = round_.day_best(t);
    hud.rounds_today = round_.rounds_today(t);
    hud.notice = input_problem_words(watch_.problem(t));
    hud.num_blocks = static_cast<int>(scene_.blocks().size());
    hud.overhang = scene_.overhang();
    hud.best_overhang = best_overhang_.best_for(hud.num_blocks);
    hud.best_known_up_to = best_overhang_.largest();
    hud.condition = condition_;
    hud.instruction = drawn_instruction_;
    hud.problem = drawn_problem_;
    renderer_->draw_game(scene_, mapping_, hud, (t - start_utime_) / 1000);
  }
  display_->present();
  ++frames_presented_;
  if (prediction_received_) {
    const int64_t elapsed = std::chrono::duration_cast<std::chrono::microseconds>(
                                std::chrono::steady_clock::now() - *prediction_received_)
                                .count();
    latencies_us_.push_back(elapsed);
    if (latencies_us_.size() > 100000) latencies_us_.erase(latencies_us_.begin(), latencies_us_.begin() + 50000);
    publish_report(timing_channel_, messages::make_timing("projection", "present", scene_.stack_utime(),
                                                          scene_.stack_frame(), elapsed, prediction_received_utime_));
    prediction_received_.reset();
  }
  dirty_ = false;
  unpublished_frame_ = true;
}

void ProjectionNode::publish_status_image(const cv::Mat& frame, int64_t t) {
  const int w = std::min(config_.status_image_width, frame.cols);
  const int h = std::max(1, static_cast<int>(std::lround(static_cast<double>(w) * frame.rows / frame.cols)));
  cv::Mat small;
  cv::resize(frame, small, cv::Size(w, h), 0, 0, cv::INTER_AREA);
  image_t im{};
  if (!cv::imencode(".jpg", small, im.data, {cv::IMWRITE_JPEG_QUALITY, 80})) {
    error("failed status images", "cannot encode the projector image as JPEG");
    return;
  }
  im.utime = t;
  im.frame_number = ++status_images_;
  im.width = small.cols;
  im.height = small.rows;
  im.format = image_t::FORMAT_JPEG;
  im.source = "projector";
  im.size = static_cast<int32_t>(im.data.size());
  publish(channel(kProjectorImageChannel), im);
}

void ProjectionNode::capture_if_due() {
  const int64_t t = now();
  const bool state_due = unpublished_frame_ &&
                         (last_state_utime_ < 0 || t - last_state_utime_ >= static_cast<int64_t>(1e6 / config_.state_hz));
  const bool periodic_snapshot = !config_.snapshot_dir.empty() && t >= next_snapshot_utime_;
  const bool requested_snapshot = snapshot_requested_ && !config_.snapshot_dir.empty();
  if (snapshot_requested_ && config_.snapshot_dir.empty()) {
    warn("snapshots without a folder", "snapshot requested but no --snapshot-dir given");
    snapshot_requested_ = false;
  }
  const bool status_image_due = t >= next_status_image_utime_;
  // A frame waiting for its state message: wake when the rate allows it.
  if (unpublished_frame_ && !state_due) wake_at(last_state_utime_ + static_cast<int64_t>(1e6 / config_.state_hz));
  if (!status_image_due && next_status_image_utime_ != INT64_MAX) wake_at(next_status_image_utime_);
  if (!state_due && !periodic_snapshot && !requested_snapshot && !status_image_due) return;

  cv::Mat frame = display_->read_frame();
  if (status_image_due) {
    // Sent even when nothing changed: its age on the status page says the projection is alive.
    publish_status_image(frame, t);
    // On the runtime clock's schedule, not from when this tick happened to run: the stated rate holds.
    const auto every = static_cast<int64_t>(config_.status_image_every * 1e6);
    while (next_status_image_utime_ <= t) next_status_image_utime_ += every;
  }
  if (state_due) {
    unpublished_frame_ = false;
    const int mode = pattern_ ? projector_state_t::MODE_PATTERN : projector_state_t::MODE_GAME;
    cv::Mat image;
    if (pattern_) {
      image = frame;  // full size: calibration needs every stripe
    } else {
      const int h = std::max(1, static_cast<int>(std::lround(static_cast<double>(config_.state_width) * frame.rows / frame.cols)));
      cv::resize(frame, image, cv::Size(config_.state_width, h), 0, 0, cv::INTER_AREA);
    }
    const bool same = mode == last_state_mode_ && pattern_sequence_ == last_state_sequence_ &&
                      image.size == last_state_image_.size &&
                      std::equal(image.datastart, image.dataend, last_state_image_.datastart);
    if (!same) {
      std::vector<uint8_t> png;
      cv::imencode(".png", image, png);
      projector_state_t s{};
      s.utime = t;
      s.frame_number = pattern_ ? -1 : scene_.stack_frame();
      s.command_sequence = pattern_sequence_;
      s.mode = static_cast<int8_t>(mode);
      s.image.utime = s.utime;
      s.image.frame_number = frames_presented_;
      s.image.width = image.cols;
      s.image.height = image.rows;
      s.image.format = image_t::FORMAT_PNG;
      s.image.source = "projection";
      s.image.data = std::move(png);
      s.image.size = static_cast<int32_t>(s.image.data.size());
      publish(projector_channel_, s);
      last_state_image_ = image.clone();
      last_state_sequence_ = pattern_sequence_;
      last_state_mode_ = mode;
      last_state_utime_ = t;
    }
  }
  if (periodic_snapshot || requested_snapshot) {
    const std::filesystem::path dir(config_.snapshot_dir);
    bool ok = write_png_atomically(dir / "latest.png", frame);
    if (requested_snapshot) {
      char name[64];
      std::snprintf(name, sizeof(name), "snapshot-%04d.png", ++snapshot_count_);
      ok = write_png_atomically(dir / name, frame) && ok;
      log::info("snapshot ", (dir / name).string());
    }
    if (!ok) error("failed snapshots", "cannot write a snapshot into " + dir.string());
    snapshot_requested_ = false;
    if (periodic_snapshot) next_snapshot_utime_ = t + static_cast<int64_t>(config_.snapshot_every * 1e6);
  }
}

}  // namespace bricklayer::projection
