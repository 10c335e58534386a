// Draws what the projector shows with SDL's 2D renderer: the game display (every block filled in
// projector coordinates with its predicted colour; score, MAX and how close the pile is to the best
// possible top right; the round timer top centre; a miniature of the pile with its prediction, the
// animated collapse preview and the hint outline top left) or a calibration pattern full screen.
// The blocks' colours, the knife-edge outline, the margin text and the ghost follow the display condition
// (display_condition.h), the same decision on the board and in the miniature. While an input is stale
// (Hud::notice) the blocks lose their verdict colours (dim blue, no ghost, no hint) and the notice is
// shown in the middle: a frozen red or blue must not pass for the truth. A study session's instruction
// (Hud::instruction) is shown centred and wrapped below everything else at the top; a study problem
// (Hud::problem, problem_outline.h) as outlines of the pile to build, drawn under the blocks (a real block
// put in place covers its outline), or as a score problem's target line under the instruction.
// Every colour of the game display comes from palette.h: green stays 0 in every pixel.
#pragma once

#include <SDL.h>
#include <SDL_ttf.h>

#include <array>
#include <cstdint>
#include <functional>
#include <optional>
#include <string>

#include <opencv2/core.hpp>

#include "bricklayer/board/board_to_projector.h"
#include "bricklayer/projection/display_condition.h"
#include "bricklayer/projection/knife_edge_look.h"
#include "bricklayer/projection/palette.h"
#include "bricklayer/projection/problem_outline.h"
#include "bricklayer/projection/round_referee.h"
#include "bricklayer/projection/scene.h"

namespace bricklayer::projection {

inline constexpr const char* kDefaultFontPath = "/usr/share/fonts/truetype/dejavu/DejaVuSans-Bold.ttf";

// The numbers the head-up display shows.
struct Hud {
  int score = 0;
  int max_score = 0;
  int64_t remaining_ms = 0;
  RoundState round_state = RoundState::kIdle;
  std::optional<RoundEnd> last_end;     // why the last round ended (shown while it is over)
  bool auto_start = true;               // rounds start by themselves: idle says "place a block"
  int day_best = 0;                     // the best MAX of today's rounds
  int rounds_today = 0;                 // 0: the day's best line is not shown
  std::string notice;                   // an input problem in words ("camera not seeing"); "" = none
  int num_blocks = 0;
  double overhang = 0;                  // block lengths
  std::optional<double> best_overhang;  // best possible for num_blocks; nothing = no percentage line
  int best_known_up_to = 0;             // the table's largest block count: a larger pile is told so
  DisplayCondition condition = DisplayCondition::kProposed;  // how the pile is lit
  std::string instruction;              // a study session's words to the subject; "" = none
  ProblemView problem;                  // the study problem shown (outlines or target); empty = none
};

// Where the parts of the display were drawn in the last frame (projector pixels). Text rectangles
// are the drawn text's bounds; an empty rectangle means not drawn.
struct Layout {
  SDL_Rect score{};        // the score's number
  SDL_Rect score_label{};  // "SCORE"
  SDL_Rect max{};
  SDL_Rect best{};
  SDL_Rect timer{};
  SDL_Rect round_label{};
  SDL_Rect minimap{};
  SDL_Rect margin{};  // the margin text under the miniature (knife_edge_look.h)
  SDL_Rect day_best{};
  SDL_Rect notice{};
  SDL_Rect instruction{};  // the study session's instruction, all its lines
  SDL_Rect problem_outlines{};  // the bounds of every study problem outline drawn
  SDL_Rect problem_target{};    // a score problem's target line
};

// The line under the timer: how to start a round, or how the last one ended.
std::string round_label(const Hud& hud);

class GameRenderer {
 public:
  // Throws std::runtime_error when SDL_ttf or the font cannot be loaded (names the file).
  GameRenderer(SDL_Renderer* renderer, int width, int height, const std::string& font_path = kDefaultFontPath);
  ~GameRenderer();
  GameRenderer(const GameRenderer&) = delete;
  GameRenderer& operator=(const GameRenderer&) = delete;

  // anim_ms drives the collapse preview's animation (any monotonic milliseconds).
  void draw_game(const Scene& scene, const board::BoardToProjector& mapping, const Hud& hud, int64_t anim_ms);
  // A BGR (CV_8UC3) or grey (CV_8UC1) image stretched over the whole projector image.
  void draw_pattern(const cv::Mat& image);
  const Layout& layout() const { return layout_; }

 private:
  struct Text {
    std::string text;
    Rgb colour{};
    SDL_Texture* texture = nullptr;
    int w = 0;
    int h = 0;
  };
  enum Slot { kScore, kScoreLabel, kMax, kBest, kTimer, kRoundLabel, kDayBest, kNotice, kMargin, kInstruction, kProblemTarget, kSlotCount };
  // Draws text with its top edge at y; align: 0 left of x, 1 centred on x, 2 right of x. wrap > 0: lines
  // broken at spaces to at most wrap pixels (centred lines when align is 1).
  SDL_Rect draw_text(Slot slot, TTF_Font* font, const std::string& text, Rgb colour, int x, int y, int align, int wrap = 0);
  void fill_quad(const std::array<SDL_FPoint, 4>& corners, Rgb colour);
  void outline(const SDL_FPoint* points, int count, Rgb colour);
  void draw_blocks(const Scene& scene, const board::BoardToProjector& mapping, const PileLook& look, int64_t anim_ms);
  void draw_hud(const Hud& hud);
  void draw_instruction(const Hud& hud);  // a study session's words, below everything at the top
  void draw_problem_outlines(const ProblemView& problem, const board::BoardToProjector& mapping, double block_height);
  void draw_problem_target(const Hud& hud);  // under the instruction
  int below_top_parts() const;  // the first row free below the miniature, the timer and the score column
  void draw_minimap(const Scene& scene, const PileLook& look, int64_t anim_ms, bool stale);
  void draw_margin(const Scene& scene, const PileLook& look, int64_t anim_ms);  // knife_edge_look.h's text
  void outline_blocks(const KnifeEdgeLook& look, const Scene& scene, const std::function<SDL_FPoint(double, double)>& at,
                      int width);

  SDL_Renderer* renderer_;
  int width_;
  int height_;
  TTF_Font* font_big_ = nullptr;
  TTF_Font* font_mid_ = nullptr;
  TTF_Font* font_small_ = nullptr;
  std::array<Text, kSlotCount> texts_{};
  SDL_Texture* pattern_ = nullptr;
  Layout layout_{};
};

}  // namespace bricklayer::projection
