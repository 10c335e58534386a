#include "bricklayer/projection/projection_app.h"

#include <poll.h>

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <filesystem>
#include <stdexcept>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "bricklayer/common/channels.h"
#include "bricklayer/common/log.h"
#include "bricklayer/projection/round_book.h"
#include "bricklayer/projector_state_t.hpp"
#include "bricklayer/round_t.hpp"
#include "bricklayer/timing_t.hpp"

#include "bricklayer/patterns/patterns.h"

namespace bricklayer::projection {

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
}  // namespace

ProjectionApp::ProjectionApp(const ProjectionOptions& options)
    : options_(options),
      module_("projection", options.lcm_url),
      stack_in_(module_.counters()),
      prediction_in_(module_.counters()),
      calibration_in_(module_.counters()),
      hint_in_(module_.counters()),
      preview_in_(module_.counters()),
      round_(options.rounds),
      watch_(wall_utime(), static_cast<int64_t>(options.stale_after_s * 1e6)),
      debounce_(options.beep_hold_ms, options.beep_rearm_ms),
      started_(std::chrono::steady_clock::now()) {
  if (!(options.stale_after_s >= 0)) throw std::invalid_argument("--stale-seconds must be >= 0");
  if (options.fps < 1 || options.fps > 1000) throw std::invalid_argument("--fps must be in 1..1000");
  if (options.state_width < 16 || options.state_width > options.display.width)
    throw std::invalid_argument("--state-width must be in 16.." + std::to_string(options.display.width));
  if (!(options.state_max_hz > 0)) throw std::invalid_argument("--state-hz must be positive");
  if (options.snapshot_every_s < 0) throw std::invalid_argument("--snapshot-every must be >= 0");
  if (!options.snapshot_dir.empty()) {
    std::error_code ec;
    std::filesystem::create_directories(options.snapshot_dir, ec);
    if (ec || !std::filesystem::is_directory(options.snapshot_dir))
      throw std::runtime_error("cannot create the snapshot folder '" + options.snapshot_dir + "': " + ec.message());
  } else if (options.snapshot_every_s > 0) {
    throw std::invalid_argument("--snapshot-every needs --snapshot-dir");
  }
  if (!options.best_overhang_path.empty()) {
    try {
      best_overhang_ = BestOverhang::load(options.best_overhang_path);
    } catch (const std::exception& e) {
      log::warn(e.what(), "; the best-overhang line is not shown");
    }
  }

  restore_rounds();

  display_ = std::make_unique<Display>(options.display);
  renderer_ = std::make_unique<GameRenderer>(display_->renderer(), options.display.width, options.display.height,
                                             options.font_path);
  if (!options.mute) beeper_ = std::make_unique<Beeper>(options.tone);

  module_.subscribe<stack_t>(channel(kStackChannel), [this](const stack_t& m) { stack_in_.put(m); });
  module_.subscribe<prediction_t>(channel(kPredictionChannel), [this](const prediction_t& m) {
    prediction_in_.put(m);
    prediction_stamp_ = Stamped{now_us(), wall_utime()};
  });
  module_.subscribe<calibration_t>(channel(kCalibrationChannel), [this](const calibration_t& m) { calibration_in_.put(m); });
  module_.subscribe<hint_t>(channel(kHintChannel), [this](const hint_t& m) { hint_in_.put(m); });
  module_.subscribe<collapse_preview_t>(channel(kPreviewChannel), [this](const collapse_preview_t& m) { preview_in_.put(m); });
  module_.subscribe<command_t>(channel(kCommandChannel), [this](const command_t& m) {
    if (commands_in_.size() >= 1000) {  // a flood: keep the newest thousand
      commands_in_.erase(commands_in_.begin());
      ++module_.counters().dropped;
    }
    commands_in_.push_back(m);
  });
  next_snapshot_ms_ = options.snapshot_every_s > 0 ? 0 : INT64_MAX;
}

ProjectionApp::~ProjectionApp() = default;

int64_t ProjectionApp::now_us() const {
  return std::chrono::duration_cast<std::chrono::microseconds>(std::chrono::steady_clock::now() - started_).count();
}
int64_t ProjectionApp::now_ms() const { return now_us() / 1000; }
int64_t ProjectionApp::clock_utime() const { return wall_utime(); }

void ProjectionApp::restore_rounds() {
  if (options_.rounds_file.empty()) return;
  RoundBook book;
  try {
    book = load_round_book(options_.rounds_file);
  } catch (const std::exception& e) {
    // Kept aside for a person to look at; the exhibit goes on with a fresh book.
    const std::string aside = options_.rounds_file + ".damaged";
    std::error_code ec;
    std::filesystem::rename(options_.rounds_file, aside, ec);
    ++module_.counters().errors;
    log::error(e.what(), "; kept as ", aside, ", starting a new round book");
  }
  const size_t rounds = book.history.size();
  const bool running = book.running.has_value();
  round_.restore(std::move(book.history), book.running, clock_utime());
  saved_revision_ = round_.revision();
  if (rounds > 0 || running)
    log::info("round book ", options_.rounds_file, ": ", rounds, " round(s)", running ? ", one running" : "",
              "; today's best ", round_.day_best(clock_utime()));
  if (running && round_.state() != RoundState::kRunning) save_rounds();  // closed while we were down
}

void ProjectionApp::save_rounds() {
  if (options_.rounds_file.empty()) return;
  try {
    save_round_book(options_.rounds_file, RoundBook{round_.history(), round_.running()});
    saved_revision_ = round_.revision();
  } catch (const std::exception& e) {
    ++module_.counters().errors;
    saved_revision_ = round_.revision();  // tried: the next change tries again, no retry storm
    log::error(e.what());
  }
}

int ProjectionApp::run() {
  Module::install_signal_handlers();
  const int64_t frame_ms = std::max(1, 1000 / options_.fps);
  while (!quit_ && !Module::stop_requested()) {
    const int64_t now = now_ms();
    if (now >= next_refresh_ms_) next_refresh_ms_ = now + frame_ms;
    step(static_cast<int>(std::clamp<int64_t>(next_refresh_ms_ - now, 0, frame_ms)));
  }
  log::info("stopping: received ", module_.counters().received.load(), ", published ",
            module_.counters().published.load(), ", dropped ", module_.counters().dropped.load(), ", errors ",
            module_.counters().errors.load(), ", frames ", frames_presented_);
  module_.publish_heartbeat();
  return 0;
}

void ProjectionApp::wait_for_bus(int wait_ms) {
  pollfd fd{module_.lcm().getFileno(), POLLIN, 0};
  const int ready = ::poll(&fd, 1, std::max(0, wait_ms));
  if (ready < 0 && errno != EINTR) {
    ++module_.counters().errors;
    log::error("poll on the LCM socket failed");
    return;
  }
  // Drain what is queued without ever blocking (bounded, so a flood cannot starve the display).
  for (int k = 0; k < 1000; ++k) {
    const int rc = module_.lcm().handleTimeout(0);
    if (rc <= 0) {
      if (rc < 0) ++module_.counters().errors;
      break;
    }
  }
}

// A new stack is drawn together with its prediction. Drawing it alone (its colours still unknown) would
// spend a whole draw just before the prediction arrives (a fraction of a millisecond later) and delay the
// frame that matters by that draw. So while predictions are flowing, a new stack waits for its own
// prediction up to kPredictionHoldMs; without a prediction process it is drawn at once.
constexpr int64_t kPredictionHoldMs = 15;
constexpr int64_t kPredictionsFlowingMs = 2000;

bool ProjectionApp::awaiting_prediction() const {
  const int64_t now = now_ms();
  return stack_arrived_ms_ >= 0 && now - stack_arrived_ms_ < kPredictionHoldMs &&
         now - last_prediction_ms_ < kPredictionsFlowingMs && !pattern_ && scene_.prediction_for_stack() == nullptr;
}

void ProjectionApp::step(int wait_ms) {
  if (awaiting_prediction())
    wait_ms = std::min<int>(wait_ms, static_cast<int>(std::max<int64_t>(1, stack_arrived_ms_ + kPredictionHoldMs - now_ms())));
  wait_for_bus(wait_ms);
  handle_events();
  try {
    apply_inputs();
    tick();
    const bool animating = !pattern_ && scene_.preview_for_stack() != nullptr;
    const bool refresh = display_->mode() != DisplayMode::kHeadless;  // a real screen redraws every refresh
    if ((dirty_ || animating || refresh) && !awaiting_prediction()) draw_and_present();
    capture_if_due();
  } catch (const std::exception& e) {
    ++module_.counters().errors;
    log::error("projection step failed: ", e.what());
  }
}

void ProjectionApp::handle_events() {
  SDL_Event event;
  while (SDL_PollEvent(&event)) {
    if (event.type == SDL_QUIT) quit_ = true;
    if (event.type == SDL_WINDOWEVENT) dirty_ = true;
    if (event.type != SDL_KEYDOWN || event.key.repeat) continue;
    switch (event.key.keysym.sym) {
      case SDLK_ESCAPE:
      case SDLK_q: quit_ = true; break;
      case SDLK_s: round_.start(clock_utime()); dirty_ = true; break;
      case SDLK_r: round_.reset(clock_utime()); dirty_ = true; break;
      case SDLK_h: request_hint(); break;
      case SDLK_p: snapshot_requested_ = true; break;
      default: break;
    }
  }
}

void ProjectionApp::request_hint() {
  command_t c{};
  c.utime = wall_utime();
  c.command = command_t::REQUEST_HINT;
  c.sequence = ++hint_sequence_;
  module_.publish(channel(kCommandChannel), c);
}

void ProjectionApp::apply_inputs() {
  // bricklayer-calibrate --serve republishes the calibration every second: an unchanged one is not applied
  // (nor logged) again.
  if (auto c = calibration_in_.take(); c && !(applied_calibration_ && same_message(*applied_calibration_, *c))) {
    applied_calibration_ = *c;
    try {
      board::BoardToProjector mapping = board::BoardToProjector::from_calibration(*c);
      if (c->projector_width > 0 && c->projector_height > 0 &&
          (c->projector_width != display_->width() || c->projector_height != display_->height())) {
        // The same projector at another resolution: scale its pixels to ours.
        const double sx = static_cast<double>(display_->width()) / c->projector_width;
        const double sy = static_cast<double>(display_->height()) / c->projector_height;
        std::array<double, 9> c2p{};
        for (int k = 0; k < 9; ++k) c2p[k] = c->camera_to_projector[k];
        std::array<double, 9> c2b{};
        for (int k = 0; k < 9; ++k) c2b[k] = c->camera_to_board[k];
        mapping = board::BoardToProjector::from_homographies(board::multiply3({sx, 0, 0, 0, sy, 0, 0, 0, 1}, c2p), c2b);
        log::warn("calibration is for a ", c->projector_width, "x", c->projector_height, " projector; scaled to ",
                  display_->width(), "x", display_->height());
      }
      mapping_ = mapping;
      dirty_ = true;
      log::info("calibration applied (reprojection error mean ", c->reprojection_error_mean_px, " px)");
    } catch (const std::exception& e) {
      ++module_.counters().errors;
      log::warn("calibration rejected: ", e.what());
    }
  }
  for (const command_t& c : commands_in_) apply_command(c);
  commands_in_.clear();
  if (auto s = stack_in_.take()) {
    try {
      const int rejected = scene_.set_stack(*s);
      if (rejected > 0) {
        module_.counters().errors += rejected;
        log::warn(rejected, " block(s) of frame ", s->frame_number, " rejected (non-finite x or bad row)");
      }
      dirty_ = true;
      stack_arrived_ms_ = now_ms();
      // Only a measurement says what is on the board: a frame that could not be read or a covered
      // board is neither empty nor a pile, and counts as the camera not seeing.
      if (s->status == stack_t::STATUS_OK) {
        const int64_t now = clock_utime();
        watch_.stack_seen(now);
        round_.board_seen(now, static_cast<int>(scene_.blocks().size()));
      }
    } catch (const std::exception& e) {
      ++module_.counters().errors;
      log::warn("stack rejected: ", e.what());
    }
  }
  if (auto p = prediction_in_.take()) {
    try {
      scene_.set_prediction(*p);
      last_prediction_ms_ = now_ms();
      watch_.prediction_seen(clock_utime());
      pending_latency_ = prediction_stamp_;
      dirty_ = true;
    } catch (const std::exception& e) {
      ++module_.counters().errors;
      log::warn("prediction rejected: ", e.what());
    }
  }
  if (auto p = preview_in_.take()) {
    try {
      scene_.set_preview(*p);
      dirty_ = true;
    } catch (const std::exception& e) {
      ++module_.counters().errors;
      log::warn("collapse preview rejected: ", e.what());
    }
  }
  if (auto h = hint_in_.take()) {
    try {
      scene_.set_hint(*h);
      dirty_ = true;
    } catch (const std::exception& e) {
      ++module_.counters().errors;
      log::warn("hint rejected: ", e.what());
    }
  }
}

void ProjectionApp::apply_command(const command_t& c) {
  switch (c.command) {
    case command_t::START_ROUND: round_.start(clock_utime()); dirty_ = true; break;
    case command_t::RESET_ROUND: round_.reset(clock_utime()); dirty_ = true; break;
    case command_t::SHOW_PATTERN:
      try {
        cv::Mat image = render_command_pattern(c, display_->width(), display_->height());
        pattern_ = image;
        pattern_sequence_ = c.sequence;
        dirty_ = true;
      } catch (const std::exception& e) {
        ++module_.counters().errors;
        log::warn("cannot show pattern ", c.pattern, " index ", c.index, ": ", e.what());
      }
      break;
    case command_t::CLEAR_PATTERN:
      pattern_.reset();
      pattern_sequence_ = c.sequence;
      dirty_ = true;
      break;
    case command_t::CLEAR_HINT: scene_.clear_hint(); dirty_ = true; break;
    case command_t::SNAPSHOT: snapshot_requested_ = true; break;
    default: break;  // REQUEST_HINT, SELF_CHECK: for other modules
  }
}

void ProjectionApp::tick() {
  const int64_t now = now_ms();
  const prediction_t* p = scene_.prediction_for_stack();
  const bool balanced = p && p->status == prediction_t::STATUS_OK && p->balanced;
  const int64_t clock = clock_utime();
  const InputProblem problem = watch_.problem(clock);
  if (problem != shown_problem_) {
    shown_problem_ = problem;
    dirty_ = true;
    if (problem == InputProblem::kNone) log::info("inputs are back");
    else log::warn(watch_.status(clock));
  }
  // A stale verdict scores nothing: MAX takes only what is live.
  round_.pile(clock, scene_.score(), balanced && problem == InputProblem::kNone, static_cast<int>(scene_.blocks().size()));
  const bool round_changed = round_.update(clock);
  if (round_changed) dirty_ = true;
  if (round_.revision() != saved_revision_) save_rounds();
  if (round_changed || now >= next_round_publish_ms_) {
    publish_round();
    next_round_publish_ms_ = now + 1000;
  }
  if (debounce_.update(!pattern_ && problem == InputProblem::kNone && scene_.any_cause(), now) && beeper_)
    beeper_->beep();
  if (now >= next_heartbeat_ms_) {
    if (!latencies_us_.empty()) {
      std::vector<int64_t> recent(latencies_us_.end() - std::min<size_t>(latencies_us_.size(), 200), latencies_us_.end());
      std::nth_element(recent.begin(), recent.begin() + recent.size() / 2, recent.end());
      module_.set_value("present_p50_ms", recent[recent.size() / 2] / 1000.0);
    }
    module_.set_value("frames", static_cast<double>(frames_presented_));
    module_.set_value("calibrated", mapping_.calibrated() ? 1 : 0);
    module_.set_value("day_best", round_.day_best(clock));
    module_.set_value("rounds_today", round_.rounds_today(clock));
    const std::string stale = watch_.status(clock);
    module_.set_status(pattern_ ? "pattern" : stale.empty() ? "ok" : stale);
    module_.publish_heartbeat();
    next_heartbeat_ms_ = now + 1000;
  }
}

void ProjectionApp::publish_round() {
  round_t r{};
  r.utime = clock_utime();
  r.state = static_cast<int8_t>(round_.state());
  r.duration_ms = round_.duration_ms();
  r.remaining_ms = round_.remaining_ms(r.utime);
  r.score = round_.score();
  r.max_score = round_.max_score();
  r.num_blocks = static_cast<int32_t>(scene_.blocks().size());
  r.best_possible = best_overhang_.best_for(r.num_blocks).value_or(0.0);
  module_.publish(channel(kRoundChannel), r);
}

void ProjectionApp::draw_and_present() {
  display_->begin_frame();
  if (pattern_) {
    renderer_->draw_pattern(*pattern_);
  } else {
    Hud hud;
    hud.score = round_.score();
    hud.max_score = round_.max_score();
    const int64_t clock = clock_utime();
    hud.remaining_ms = round_.remaining_ms(clock);
    hud.round_state = round_.state();
    if (const RoundRecord* last = round_.last_round()) hud.last_end = last->end;
    hud.auto_start = round_.rules().auto_start;
    hud.day_best = round_.day_best(clock);
    hud.rounds_today = round_.rounds_today(clock);
    hud.notice = input_problem_words(watch_.problem(clock));
    hud.num_blocks = static_cast<int>(scene_.blocks().size());
    hud.overhang = scene_.overhang();
    hud.best_overhang = best_overhang_.best_for(hud.num_blocks);
    renderer_->draw_game(scene_, mapping_, hud, now_ms());
  }
  display_->present();
  ++frames_presented_;
  if (pending_latency_) {
    const int64_t elapsed = now_us() - pending_latency_->received_us;
    latencies_us_.push_back(elapsed);
    if (latencies_us_.size() > 100000) latencies_us_.erase(latencies_us_.begin(), latencies_us_.begin() + 50000);
    timing_t t{};
    t.utime = scene_.stack_utime();
    t.frame_number = scene_.stack_frame();
    t.module = "projection";
    t.stage = "present";
    t.elapsed_us = elapsed;
    t.received_utime = pending_latency_->received_utime;
    module_.lcm().publish(channel(kTimingChannel), &t);
    pending_latency_.reset();
  }
  dirty_ = false;
  unpublished_frame_ = true;
}

void ProjectionApp::capture_if_due() {
  const int64_t now = now_us();
  const bool state_due = unpublished_frame_ &&
                         (last_state_us_ < 0 || now - last_state_us_ >= static_cast<int64_t>(1e6 / options_.state_max_hz));
  const bool periodic_snapshot = !options_.snapshot_dir.empty() && now / 1000 >= next_snapshot_ms_;
  const bool requested_snapshot = snapshot_requested_ && !options_.snapshot_dir.empty();
  if (snapshot_requested_ && options_.snapshot_dir.empty()) {
    log::warn("snapshot requested but no --snapshot-dir given");
    snapshot_requested_ = false;
  }
  if (!state_due && !periodic_snapshot && !requested_snapshot) return;

  cv::Mat frame = display_->read_frame();
  if (state_due) {
    unpublished_frame_ = false;
    const int mode = pattern_ ? projector_state_t::MODE_PATTERN : projector_state_t::MODE_GAME;
    cv::Mat image;
    if (pattern_) {
      image = frame;  // full size: calibration needs every stripe
    } else {
      const int h = std::max(1, static_cast<int>(std::lround(static_cast<double>(options_.state_width) * frame.rows / frame.cols)));
      cv::resize(frame, image, cv::Size(options_.state_width, h), 0, 0, cv::INTER_AREA);
    }
    const bool same = mode == last_state_mode_ && pattern_sequence_ == last_state_sequence_ &&
                      image.size == last_state_image_.size &&
                      std::equal(image.datastart, image.dataend, last_state_image_.datastart);
    if (!same) {
      std::vector<uint8_t> png;
      cv::imencode(".png", image, png);
      projector_state_t s{};
      s.utime = wall_utime();
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
      module_.publish(channel(kProjectorChannel), s);
      last_state_image_ = image.clone();
      last_state_sequence_ = pattern_sequence_;
      last_state_mode_ = mode;
      last_state_us_ = now;
    }
  }
  if (periodic_snapshot || requested_snapshot) {
    const std::filesystem::path dir(options_.snapshot_dir);
    bool ok = write_png_atomically(dir / "latest.png", frame);
    if (requested_snapshot) {
      char name[64];
      std::snprintf(name, sizeof(name), "snapshot-%04d.png", ++snapshot_count_);
      ok = write_png_atomically(dir / name, frame) && ok;
      log::info("snapshot ", (dir / name).string());
    }
    if (!ok) {
      ++module_.counters().errors;
      log::warn("cannot write a snapshot into ", dir.string());
    }
    snapshot_requested_ = false;
    if (periodic_snapshot)
      next_snapshot_ms_ = now / 1000 + static_cast<int64_t>(options_.snapshot_every_s * 1000);
  }
}

}  // namespace bricklayer::projection
