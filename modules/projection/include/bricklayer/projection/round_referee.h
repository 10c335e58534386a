// The rounds of an unattended exhibit. A round starts by itself when blocks appear on a board that was
// seen empty (held for a while, so a hand passing by does not start one), lasts its duration, and ends
// early when the board stays empty; START and RESET (keys, BL_COMMAND) still start and reset rounds.
// It keeps the score, the round's MAX (the best *balanced* score while the round runs), the history of
// finished rounds and the day's best.
//
// Pure and clock-driven: every call takes the time (microseconds since the epoch, from the runtime's
// clock or a message's utime), so a test steps through every transition without waiting and a recorded
// run replays the same rounds. The board is judged only from the stacks seen: a camera that stops
// delivering never counts as an empty (or a steady) board.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace bricklayer::projection {

enum class RoundState : int8_t { kIdle = 0, kRunning = 1, kEnded = 2 };  // = round_t::STATE_*

// Why a round ended.
enum class RoundEnd : int8_t {
  kTimeUp = 0,        // its duration passed
  kBoardCleared = 1,  // the board stayed empty (the players left)
  kRestarted = 2,     // START while it ran: a fresh round took its place
  kReset = 3,         // RESET while it ran
};
const char* round_end_name(RoundEnd end);  // "time up", "board cleared", "restarted", "reset"
std::optional<RoundEnd> parse_round_end(const std::string& name);

// One round as the history keeps it.
struct RoundRecord {
  int64_t start_utime = 0;
  int64_t end_utime = 0;  // 0 while it runs
  int max_score = 0;      // its MAX: the best balanced score while it ran
  int blocks = 0;         // blocks in the pile that scored MAX (0 when no balanced pile scored)
  int most_blocks = 0;    // most blocks on the board while it ran
  RoundEnd end = RoundEnd::kTimeUp;
  bool operator==(const RoundRecord&) const = default;
};

struct RoundRules {
  int64_t duration_us = 180'000'000;  // a round's length
  int64_t start_hold_us = 2'000'000;  // blocks on the board this long, without a gap: a round starts
  int64_t arm_empty_us = 1'000'000;   // the board seen empty this long: the next blocks may start a round
  int64_t end_empty_us = 20'000'000;  // the board empty this long while a round runs: it ends early
  int64_t max_gap_us = 1'000'000;     // stacks further apart than this: the board's history starts again
  bool auto_start = true;             // false: only START begins a round
  size_t history_limit = 1000;        // finished rounds kept (the oldest go first)
};

class RoundReferee {
 public:
  // Throws std::invalid_argument for a non-positive duration or a negative hold.
  explicit RoundReferee(const RoundRules& rules);

  // A stack was seen at now with this many blocks on the board: the debounce's input.
  void board_seen(int64_t now, int blocks);
  // The drawn pile now: its score, whether its prediction says balanced, its blocks. MAX takes the
  // score only while a round runs and only when balanced.
  void pile(int64_t now, int score, bool balanced, int blocks);
  // START: a fresh round now (a running one ends as kRestarted). RESET: idle, MAX 0 (a running one
  // ends as kReset). Both need the board to be seen empty again before a round starts by itself.
  void start(int64_t now);
  void reset(int64_t now);
  // Ends a round whose time is up. Returns true when anything shown (state, whole seconds left, score,
  // MAX, the day's best) changed since the previous call.
  bool update(int64_t now);

  // After a restart: the saved history, and the round that was running then. A running round whose
  // time is up by now is closed at its scheduled end; one still in time runs on. Between rounds the
  // last round is shown as ended (idle when it was reset).
  void restore(std::vector<RoundRecord> history, std::optional<RoundRecord> running, int64_t now);

  const RoundRules& rules() const { return rules_; }
  RoundState state() const { return state_; }
  int64_t duration_ms() const { return rules_.duration_us / 1000; }
  int64_t remaining_ms(int64_t now) const;
  int score() const { return score_; }
  // The running round's MAX; between rounds the last round's (0 after RESET or before any round).
  int max_score() const;
  // The running round, if any.
  const std::optional<RoundRecord>& running() const { return running_; }
  // Finished rounds, oldest first.
  const std::vector<RoundRecord>& history() const { return history_; }
  // The newest finished round, if any.
  const RoundRecord* last_round() const { return history_.empty() ? nullptr : &history_.back(); }
  // The best MAX of the rounds that started on now's local calendar day (the running one included).
  int day_best(int64_t now) const;
  int rounds_today(int64_t now) const;  // rounds started today, the running one included
  // Grows whenever what must be saved changes (a round started, ended, a new MAX): a saver writes
  // the history when it differs from the revision it wrote last.
  uint64_t revision() const { return revision_; }

 private:
  void advance(int64_t now);  // time up
  void finish(int64_t end_utime, RoundEnd why);
  void begin(int64_t now);
  // The day's best and count, recomputed only when the history or the day changed (a display asks
  // for them every frame).
  void count_today(int64_t now) const;

  RoundRules rules_;
  RoundState state_ = RoundState::kIdle;
  std::optional<RoundRecord> running_;
  std::vector<RoundRecord> history_;
  int score_ = 0;
  bool reset_ = false;  // idle after RESET: MAX shows 0 instead of the last round's

  // The board's debounce, on the times of the stacks seen.
  std::optional<int64_t> last_seen_;
  std::optional<int64_t> empty_since_;
  std::optional<int64_t> blocks_since_;
  bool armed_ = false;  // seen empty long enough since the last round began

  uint64_t revision_ = 0;
  bool changed_ = true;
  int64_t shown_seconds_ = -1;
  int shown_day_best_ = -1;
  struct Today {
    uint64_t revision = 0;
    int day = 0;
    int best = 0;
    int rounds = 0;
    bool valid = false;
  };
  mutable Today today_;
};

// The local calendar day of a time (yyyymmdd), by the process's time zone.
int local_day(int64_t utime);

}  // namespace bricklayer::projection
