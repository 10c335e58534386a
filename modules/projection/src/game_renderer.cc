#include "bricklayer/projection/game_renderer.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <vector>

namespace bricklayer::projection {

namespace {
SDL_Color sdl_colour(Rgb c) { return SDL_Color{c.r, 0, c.b, 255}; }

// Projector pixel coordinates have pixel centres at integers (OpenCV's convention, as calibration and
// simcam use); SDL's pixel i covers [i, i+1].
SDL_FPoint to_sdl(board::Point2 p) { return SDL_FPoint{static_cast<float>(p.x + 0.5), static_cast<float>(p.y + 0.5)}; }

bool finite(const SDL_FPoint& p) { return std::isfinite(p.x) && std::isfinite(p.y); }

std::string clock_text(int64_t remaining_ms) {
  const int64_t seconds = (std::max<int64_t>(remaining_ms, 0) + 999) / 1000;
  char buffer[32];
  std::snprintf(buffer, sizeof(buffer), "%lld:%02lld", static_cast<long long>(seconds / 60),
                static_cast<long long>(seconds % 60));
  return buffer;
}
}  // namespace

GameRenderer::GameRenderer(SDL_Renderer* renderer, int width, int height, const std::string& font_path)
    : renderer_(renderer), width_(width), height_(height) {
  if (!TTF_WasInit() && TTF_Init() != 0) throw std::runtime_error(std::string("cannot initialise SDL_ttf: ") + TTF_GetError());
  // Sizes relative to the projector image so the text stays readable across a room at any resolution:
  // at 768 lines the score is ~70 px high, about 6 cm on a 2 m wide image.
  font_big_ = TTF_OpenFont(font_path.c_str(), std::max(8, height / 11));
  font_mid_ = TTF_OpenFont(font_path.c_str(), std::max(8, height / 17));
  font_small_ = TTF_OpenFont(font_path.c_str(), std::max(8, height / 32));
  if (!font_big_ || !font_mid_ || !font_small_) {
    std::string message = "cannot load the font '" + font_path + "': " + TTF_GetError() +
                          " (install fonts-dejavu-core or pass --font FILE.ttf)";
    if (font_big_) TTF_CloseFont(font_big_);
    if (font_mid_) TTF_CloseFont(font_mid_);
    if (font_small_) TTF_CloseFont(font_small_);
    throw std::runtime_error(message);
  }
}

GameRenderer::~GameRenderer() {
  for (Text& t : texts_)
    if (t.texture) SDL_DestroyTexture(t.texture);
  if (pattern_) SDL_DestroyTexture(pattern_);
  TTF_CloseFont(font_big_);
  TTF_CloseFont(font_mid_);
  TTF_CloseFont(font_small_);
}

SDL_Rect GameRenderer::draw_text(Slot slot, TTF_Font* font, const std::string& text, Rgb colour, int x, int y,
                                 int align, int wrap) {
  Text& t = texts_[slot];
  if (!t.texture || t.text != text || t.colour.r != colour.r || t.colour.b != colour.b) {
    if (t.texture) SDL_DestroyTexture(t.texture);
    t = Text{text, colour, nullptr, 0, 0};
    if (text.empty()) return SDL_Rect{};
    SDL_Surface* surface = nullptr;
    if (wrap > 0) {
      // The fonts are shared by every slot: the alignment is set for this text and put back.
      TTF_SetFontWrappedAlign(font, align == 1 ? TTF_WRAPPED_ALIGN_CENTER : align == 2 ? TTF_WRAPPED_ALIGN_RIGHT
                                                                                      : TTF_WRAPPED_ALIGN_LEFT);
      surface = TTF_RenderUTF8_Blended_Wrapped(font, text.c_str(), sdl_colour(colour), static_cast<Uint32>(wrap));
      TTF_SetFontWrappedAlign(font, TTF_WRAPPED_ALIGN_LEFT);
    } else {
      surface = TTF_RenderUTF8_Blended(font, text.c_str(), sdl_colour(colour));
    }
    if (!surface) return SDL_Rect{};
    t.texture = SDL_CreateTextureFromSurface(renderer_, surface);
    t.w = surface->w;
    t.h = surface->h;
    SDL_FreeSurface(surface);
    if (!t.texture) return SDL_Rect{};
    // Blending onto black multiplies the text's colour by its coverage: green stays 0.
    SDL_SetTextureBlendMode(t.texture, SDL_BLENDMODE_BLEND);
  }
  SDL_Rect where{x, y, t.w, t.h};
  if (align == 1) where.x = x - t.w / 2;
  if (align == 2) where.x = x - t.w;
  SDL_RenderCopy(renderer_, t.texture, nullptr, &where);
  return where;
}

void GameRenderer::fill_quad(const std::array<SDL_FPoint, 4>& corners, Rgb colour) {
  for (const SDL_FPoint& p : corners)
    if (!finite(p)) return;
  SDL_Vertex v[4];
  for (int k = 0; k < 4; ++k) v[k] = SDL_Vertex{corners[k], sdl_colour(colour), SDL_FPoint{0, 0}};
  const int indices[6] = {0, 1, 2, 0, 2, 3};
  SDL_RenderGeometry(renderer_, nullptr, v, 4, indices, 6);
}

void GameRenderer::outline(const SDL_FPoint* points, int count, Rgb colour) {
  for (int k = 0; k < count; ++k)
    if (!finite(points[k])) return;
  SDL_SetRenderDrawColor(renderer_, colour.r, 0, colour.b, 255);
  SDL_RenderDrawLinesF(renderer_, points, count);
}

void GameRenderer::draw_game(const Scene& scene, const board::BoardToProjector& mapping, const Hud& hud, int64_t anim_ms) {
  SDL_SetRenderDrawBlendMode(renderer_, SDL_BLENDMODE_NONE);
  const bool stale = !hud.notice.empty();
  // One decision for the board and the miniature (stale: every flag off, every block dim).
  const PileLook look = pile_look(hud.condition, scene, stale);
  // Under the blocks: a real block put where the problem wants it covers its outline with its verdict.
  draw_problem_outlines(hud.problem, mapping, scene.block_height());
  draw_blocks(scene, mapping, look, anim_ms);
  draw_minimap(scene, look, anim_ms, stale);
  draw_hud(hud);
  draw_margin(scene, look, anim_ms);
  draw_instruction(hud);
  draw_problem_target(hud);
}

void GameRenderer::draw_problem_outlines(const ProblemView& problem, const board::BoardToProjector& mapping,
                                         double block_height) {
  layout_.problem_outlines = SDL_Rect{};
  if (problem.outlines.empty()) return;
  // As thick as a knife edge's outline: seen across the room, thin beside a block's 32 px height at 768 lines.
  const double thickness = std::max(2, height_ / 150);
  float left = 1e9f, top = 1e9f, right = -1e9f, bottom = -1e9f;
  for (const ProblemBlock& b : problem.outlines) {
    for (const auto& side : outline_ring(b, block_height, mapping, thickness)) {
      std::array<SDL_FPoint, 4> corners{};
      for (size_t q = 0; q < 4; ++q) {
        corners[q] = to_sdl(side[q]);
        if (!finite(corners[q])) continue;
        left = std::min(left, corners[q].x);
        right = std::max(right, corners[q].x);
        top = std::min(top, corners[q].y);
        bottom = std::max(bottom, corners[q].y);
      }
      fill_quad(corners, kProblemOutline);
    }
  }
  if (right >= left && bottom >= top) {
    const int x0 = static_cast<int>(std::floor(left)), y0 = static_cast<int>(std::floor(top));
    layout_.problem_outlines = SDL_Rect{x0, y0, static_cast<int>(std::ceil(right)) - x0,
                                        static_cast<int>(std::ceil(bottom)) - y0};
  }
}

void GameRenderer::draw_problem_target(const Hud& hud) {
  if (hud.problem.target.empty()) {
    layout_.problem_target = SDL_Rect{};
    return;
  }
  const int margin = std::max(4, height_ / 48);
  const int top = layout_.instruction.w > 0 ? layout_.instruction.y + layout_.instruction.h : below_top_parts();
  layout_.problem_target = draw_text(kProblemTarget, font_mid_, hud.problem.target, kText, width_ / 2,
                                     top + margin / 2, 1, width_ * 80 / 100);
}

int GameRenderer::below_top_parts() const {
  const int margin = std::max(4, height_ / 48);
  int top = layout_.minimap.y + layout_.minimap.h + margin / 2 + TTF_FontLineSkip(font_small_);
  for (const SDL_Rect& r : {layout_.margin, layout_.timer, layout_.round_label, layout_.score, layout_.max, layout_.best,
                            layout_.day_best})
    if (r.w > 0) top = std::max(top, r.y + r.h);
  return top;
}

void GameRenderer::draw_instruction(const Hud& hud) {
  if (hud.instruction.empty()) {
    layout_.instruction = SDL_Rect{};
    return;
  }
  // Below everything at the top (the miniature and its margin line, the timer's lines, the score column),
  // centred and wrapped, so it covers no number and the pile, which rises from the bottom, stays in view.
  const int margin = std::max(4, height_ / 48);
  layout_.instruction = draw_text(kInstruction, font_small_, hud.instruction, kText, width_ / 2,
                                  below_top_parts() + margin / 2, 1, width_ * 60 / 100);
}

void GameRenderer::draw_margin(const Scene& scene, const PileLook& pile, int64_t anim_ms) {
  const KnifeEdgeLook look = knife_edge_look(pile.margin_text ? scene.prediction_for_stack() : nullptr, anim_ms);
  const int margin = std::max(4, height_ / 48);
  // Under the miniature, which shows the same pile.
  layout_.margin = draw_text(kMargin, font_small_, look.margin_text, look.knife_edge ? kTextWarning : kTextDim,
                             margin, layout_.minimap.y + layout_.minimap.h + margin / 2, 0);
}

// The deciding blocks of a knife edge: a red outline over their fill, drawn `width` pixels thick inwards.
void GameRenderer::outline_blocks(const KnifeEdgeLook& look, const Scene& scene,
                                  const std::function<SDL_FPoint(double, double)>& at, int width) {
  if (!look.knife_edge) return;
  for (const SceneBlock& b : scene.blocks()) {
    if (std::find(look.outlined.begin(), look.outlined.end(), b.id) == look.outlined.end()) continue;
    const SDL_FPoint c[4] = {at(b.x, b.y), at(b.x + 1, b.y), at(b.x + 1, b.y + b.height), at(b.x, b.y + b.height)};
    const SDL_FPoint centre{(c[0].x + c[2].x) / 2, (c[0].y + c[2].y) / 2};
    for (int w = 0; w < width; ++w) {
      SDL_FPoint ring[5];
      for (int q = 0; q < 4; ++q) {
        const float dx = centre.x - c[q].x, dy = centre.y - c[q].y;
        const float len = std::max(1.0f, std::sqrt(dx * dx + dy * dy));
        ring[q] = SDL_FPoint{c[q].x + dx * static_cast<float>(w) / len, c[q].y + dy * static_cast<float>(w) / len};
      }
      ring[4] = ring[0];
      outline(ring, 5, look.outline);
    }
  }
}

void GameRenderer::draw_blocks(const Scene& scene, const board::BoardToProjector& mapping, const PileLook& pile,
                               int64_t anim_ms) {
  const auto& blocks = scene.blocks();
  for (size_t k = 0; k < blocks.size(); ++k) {
    const SceneBlock& b = blocks[k];
    fill_quad({to_sdl(mapping.map(b.x, b.y)), to_sdl(mapping.map(b.x + 1, b.y)),
               to_sdl(mapping.map(b.x + 1, b.y + b.height)), to_sdl(mapping.map(b.x, b.y + b.height))},
              pile.fill[k]);
  }
  const KnifeEdgeLook look = knife_edge_look(pile.knife_edge ? scene.prediction_for_stack() : nullptr, anim_ms);
  outline_blocks(look, scene, [&](double x, double y) { return to_sdl(mapping.map(x, y)); }, std::max(2, height_ / 150));
}

void GameRenderer::draw_hud(const Hud& hud) {
  const int margin = std::max(4, height_ / 48);
  const int right = width_ - margin;
  // The number big, its label small to its left (a big "SCORE 190" would run into the timer).
  layout_.score = draw_text(kScore, font_big_, std::to_string(hud.score), kText, right, margin, 2);
  const int label_y = layout_.score.y + TTF_FontAscent(font_big_) - TTF_FontAscent(font_small_);
  layout_.score_label = draw_text(kScoreLabel, font_small_, "SCORE", kTextDim, layout_.score.x - margin / 2, label_y, 2);
  int y = layout_.score.y + std::max(layout_.score.h, TTF_FontLineSkip(font_big_));
  layout_.max = draw_text(kMax, font_mid_, "MAX " + std::to_string(hud.max_score), kText, right, y, 2);
  y = layout_.max.y + std::max(layout_.max.h, TTF_FontLineSkip(font_mid_));
  if (hud.best_overhang && *hud.best_overhang > 0 && hud.num_blocks > 0) {
    const long percent = std::lround(100.0 * std::max(0.0, hud.overhang) / *hud.best_overhang);
    char buffer[96];
    std::snprintf(buffer, sizeof(buffer), "%ld%% of the best for %d block%s (%.2f)", percent, hud.num_blocks,
                  hud.num_blocks == 1 ? "" : "s", *hud.best_overhang);
    layout_.best = draw_text(kBest, font_small_, buffer, kTextDim, right, y, 2);
    y = layout_.best.y + std::max(layout_.best.h, TTF_FontLineSkip(font_small_));
  } else if (hud.best_known_up_to > 0 && hud.num_blocks > hud.best_known_up_to) {
    // Said plainly rather than left out, so a player with a big pile knows why there is no percentage.
    const std::string line = "no best known for " + std::to_string(hud.num_blocks) + " blocks (the table goes to " +
                             std::to_string(hud.best_known_up_to) + ")";
    layout_.best = draw_text(kBest, font_small_, line, kTextDim, right, y, 2);
    y = layout_.best.y + std::max(layout_.best.h, TTF_FontLineSkip(font_small_));
  } else {
    layout_.best = SDL_Rect{};
  }
  if (hud.rounds_today > 0) {
    layout_.day_best = draw_text(kDayBest, font_small_,
                                 "BEST TODAY " + std::to_string(hud.day_best) + " (" + std::to_string(hud.rounds_today) +
                                     (hud.rounds_today == 1 ? " round)" : " rounds)"),
                                 kText, right, y, 2);
  } else {
    layout_.day_best = SDL_Rect{};
  }

  const bool warning = hud.round_state == RoundState::kRunning && hud.remaining_ms <= 10000;
  layout_.timer = draw_text(kTimer, font_big_, clock_text(hud.remaining_ms), warning ? kTextWarning : kText,
                            width_ / 2, margin, 1);
  layout_.round_label = draw_text(kRoundLabel, font_small_, round_label(hud), kTextDim, width_ / 2,
                                  layout_.timer.y + std::max(layout_.timer.h, TTF_FontLineSkip(font_big_)), 1);
  if (!hud.notice.empty()) {
    layout_.notice = draw_text(kNotice, font_mid_, hud.notice, kTextWarning, width_ / 2,
                               height_ / 2 - TTF_FontHeight(font_mid_) / 2, 1);
  } else {
    layout_.notice = SDL_Rect{};
  }
}

std::string round_label(const Hud& hud) {
  switch (hud.round_state) {
    case RoundState::kRunning: return "";
    case RoundState::kIdle: return hud.auto_start ? "place a block on the board to start" : "press S to start";
    case RoundState::kEnded: break;
  }
  std::string over = hud.last_end == RoundEnd::kTimeUp || !hud.last_end ? "TIME UP" : "ROUND OVER";
  return hud.auto_start ? over + " - clear the board to play again" : over;
}

void GameRenderer::draw_minimap(const Scene& scene, const PileLook& look, int64_t anim_ms, bool stale) {
  const int margin = std::max(4, height_ / 48);
  const SDL_Rect box{margin, margin, width_ * 28 / 100, height_ * 24 / 100};
  layout_.minimap = box;
  const double h = scene.block_height();
  const collapse_preview_t* preview = look.ghost ? scene.preview_for_stack() : nullptr;
  const hint_t* hint = stale ? nullptr : scene.hint();

  // Fit the pile (and the hint) with the surface edge in view.
  double xmin = -1.5, xmax = 1.5, ymax = 1.0;
  const double ymin = -0.3;
  for (const SceneBlock& b : scene.blocks()) {
    xmin = std::min(xmin, b.x - 0.2);
    xmax = std::max(xmax, b.x + 1.2);
    ymax = std::max(ymax, b.y + b.height + 0.2);
  }
  if (hint) {
    for (int k = 0; k < hint->num_blocks; ++k) {
      xmin = std::min(xmin, hint->xs[k] - 0.2);
      xmax = std::max(xmax, hint->xs[k] + 1.2);
      ymax = std::max(ymax, (hint->rows[k] + 1) * h + 0.2);
    }
  }
  const double pad = 4;
  const double scale = std::min((box.w - 2 * pad) / (xmax - xmin), (box.h - 2 * pad) / (ymax - ymin));
  const double x0 = box.x + pad + ((box.w - 2 * pad) - scale * (xmax - xmin)) / 2;
  auto at = [&](double x, double y) {
    return SDL_FPoint{static_cast<float>(x0 + (x - xmin) * scale),
                      static_cast<float>(box.y + box.h - pad - (y - ymin) * scale)};
  };

  const SDL_FPoint frame[5] = {{float(box.x), float(box.y)}, {float(box.x + box.w - 1), float(box.y)},
                               {float(box.x + box.w - 1), float(box.y + box.h - 1)},
                               {float(box.x), float(box.y + box.h - 1)}, {float(box.x), float(box.y)}};
  outline(frame, 5, kSurface);
  fill_quad({at(xmin, ymin), at(0, ymin), at(0, 0), at(xmin, 0)}, kSurface);
  const auto& blocks = scene.blocks();
  for (size_t k = 0; k < blocks.size(); ++k) {
    const SceneBlock& b = blocks[k];
    fill_quad({at(b.x, b.y), at(b.x + 1, b.y), at(b.x + 1, b.y + b.height), at(b.x, b.y + b.height)}, look.fill[k]);
  }
  outline_blocks(knife_edge_look(look.knife_edge ? scene.prediction_for_stack() : nullptr, anim_ms), scene, at, 2);

  // The collapse preview: the key frames played back in simulated time (linear between them), looped
  // with a pause at the end, drawn as outlines over the pile.
  if (preview && preview->num_frames > 0 && preview->num_blocks > 0) {
    const int frames = preview->num_frames;
    const double end = std::max(0.0, preview->time_s[frames - 1]);
    const double period = end + 0.8;
    const double t = std::fmod(static_cast<double>(std::max<int64_t>(anim_ms, 0)) / 1000.0, period);
    int k = 0;
    while (k + 1 < frames && preview->time_s[k + 1] <= t) ++k;
    double w = 0;
    if (k + 1 < frames) {
      const double span = preview->time_s[k + 1] - preview->time_s[k];
      w = span > 0 ? std::clamp((t - preview->time_s[k]) / span, 0.0, 1.0) : 0.0;
    }
    const int next = std::min(k + 1, frames - 1);
    for (int b = 0; b < preview->num_blocks; ++b) {
      const double* p0 = &preview->poses[3 * (k * preview->num_blocks + b)];
      const double* p1 = &preview->poses[3 * (next * preview->num_blocks + b)];
      const double cx = p0[0] + w * (p1[0] - p0[0]);
      const double cy = p0[1] + w * (p1[1] - p0[1]);
      const double angle = p0[2] + w * (p1[2] - p0[2]);
      const double c = std::cos(angle), s = std::sin(angle);
      SDL_FPoint corners[5];
      const double dx[4] = {-0.5, 0.5, 0.5, -0.5}, dy[4] = {-h / 2, -h / 2, h / 2, h / 2};
      for (int q = 0; q < 4; ++q) corners[q] = at(cx + c * dx[q] - s * dy[q], cy + s * dx[q] + c * dy[q]);
      corners[4] = corners[0];
      outline(corners, 5, kGhost);
    }
  }

  if (hint) {
    for (int k = 0; k < hint->num_blocks; ++k) {
      const double x = hint->xs[k], y = hint->rows[k] * h;
      for (int inset = 0; inset < 2; ++inset) {  // two pixels thick
        const float d = static_cast<float>(inset);
        SDL_FPoint a = at(x, y), c = at(x + 1, y + h);
        const SDL_FPoint r[5] = {{a.x + d, a.y - d}, {c.x - d, a.y - d}, {c.x - d, c.y + d}, {a.x + d, c.y + d},
                                 {a.x + d, a.y - d}};
        outline(r, 5, kHint);
      }
    }
  }
}

void GameRenderer::draw_pattern(const cv::Mat& image) {
  if (image.empty() || image.depth() != CV_8U || (image.channels() != 3 && image.channels() != 1))
    throw std::invalid_argument("a pattern must be a non-empty CV_8UC3 or CV_8UC1 image");
  cv::Mat bgr;
  if (image.channels() == 1) {
    std::vector<cv::Mat> planes{image, image, image};
    cv::merge(planes, bgr);
  } else {
    bgr = image.isContinuous() ? image : image.clone();
  }
  int tw = 0, th = 0;
  if (pattern_) SDL_QueryTexture(pattern_, nullptr, nullptr, &tw, &th);
  if (!pattern_ || tw != bgr.cols || th != bgr.rows) {
    if (pattern_) SDL_DestroyTexture(pattern_);
    pattern_ = SDL_CreateTexture(renderer_, SDL_PIXELFORMAT_BGR24, SDL_TEXTUREACCESS_STREAMING, bgr.cols, bgr.rows);
    if (!pattern_) throw std::runtime_error(std::string("cannot create the pattern texture: ") + SDL_GetError());
    SDL_SetTextureBlendMode(pattern_, SDL_BLENDMODE_NONE);
  }
  SDL_UpdateTexture(pattern_, nullptr, bgr.data, static_cast<int>(bgr.step));
  SDL_RenderCopy(renderer_, pattern_, nullptr, nullptr);
  layout_ = Layout{};
}

}  // namespace bricklayer::projection
