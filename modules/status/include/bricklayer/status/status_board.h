// What the operator's status page shows: the latest host_state_t of every host and the latest round_t,
// turned into JSON with each problem said in plain words for a non-engineer ("camera: waiting for
// camera 0", "projector-host is silent").
//
// Thread safety: the node's thread updates the board from its handlers while the HTTP server's thread
// renders it for a request; every member takes the one mutex, so a page never sees half an update. The
// board's notion of "now" is the node's bus clock, handed in by the node (set_now), never read from the
// HTTP thread: the bus is not thread-safe, and tests and replays keep their deterministic clock.
#pragma once

#include <cstdint>
#include <map>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "bricklayer/heartbeat_t.hpp"
#include "bricklayer/host_state_t.hpp"
#include "bricklayer/round_t.hpp"

namespace bricklayer::status {

// A host silent this long (no host_state_t) is reported as silent: its launcher publishes once a second.
inline constexpr double kDefaultSilentAfterS = 5.0;

// ok / warning / failed, the page's three colours.
enum class Level { ok, warning, failed };
const char* level_name(Level level);

// One module as an operator reads it: its level and, when not ok, what is wrong in plain words
// (without the module's name; the page puts it in front).
struct ModuleReading {
  Level level = Level::ok;
  std::string words;  // "" when ok
};
ModuleReading read_module(const module_state_t& m);

// The state name an operator sees: "up", "starting", "restarting", "failed", ...
const char* state_name(int8_t state);

class StatusBoard {
 public:
  explicit StatusBoard(double silent_after_s = kDefaultSilentAfterS);

  // The bus time the next render is relative to (host ages, "silent for N s").
  void set_now(int64_t utime);
  // A host's latest state replaces its previous one. Hosts are told apart by name only, so a restarted
  // launcher (a new pid) takes its host's place instead of leaving a silent twin on the page.
  void update(const host_state_t& state, int64_t received_utime);
  void update(const round_t& round);
  // A module's own heartbeat: its figures (values) are shown on its row, found by its pid. Heartbeats not
  // renewed for a minute (a process that ended) are forgotten. The serving calibrate node's heartbeat
  // (bricklayer-calibrate --serve: the one with "calibrations_done") is also the page's calibration line.
  void update(const heartbeat_t& heartbeat);

  size_t num_hosts() const;
  // The whole page's data: {"utime", "level", "problems": [...], "hosts": [...], "round": {...} | null,
  // "best_today", "calibration": {"status", "age_s", "figures"} | null}; each module of a host carries
  // "figures": {name: value} from its latest heartbeat.
  nlohmann::json to_json() const;

 private:
  nlohmann::json figures_of(int32_t pid) const;  // mutex held by the caller
  struct Host {
    host_state_t state;
    int64_t received_utime = 0;
  };
  mutable std::mutex mutex_;
  double silent_after_s_;
  int64_t now_ = 0;
  std::map<std::string, Host> hosts_;
  std::optional<round_t> round_;
  struct Figures {
    int64_t received_utime = 0;
    std::string module;
    std::vector<std::string> names;
    std::vector<double> values;
  };
  std::map<int32_t, Figures> figures_;  // by pid
  struct Calibrate {
    int64_t received_utime = 0;
    std::string status;
    nlohmann::json figures;
  };
  std::optional<Calibrate> calibrate_;  // the serving calibrate node's latest heartbeat
  // The best MAX of the day (UTC date of the round's utime) seen by this page; reset at midnight.
  int32_t best_today_ = 0;
  int64_t best_day_ = -1;
};

}  // namespace bricklayer::status
