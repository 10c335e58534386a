// A launch profile: the whole desired state of one host in one declarative file
// (launch/profiles/<name>.json), in the spirit of libbot2's procman. See modules/launcher/README.md.
#pragma once

#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "bricklayer/launcher/opening_hours.h"

namespace bricklayer::launcher {

class ProfileError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

enum class RestartPolicy { kAlways, kOnFailure, kNever };

struct ModuleSpec {
  std::string name;                          // label in the launcher's output
  std::vector<std::string> command;          // program and arguments (program: bare name or path)
  std::vector<std::string> command_with_display;  // used instead of command when $DISPLAY is set
  std::string heartbeat;                     // heartbeat_t.module to wait for; "" = no heartbeat
  RestartPolicy restart = RestartPolicy::kAlways;
  double ready_timeout_s = 10.0;             // heartbeat must arrive within this after a start
  double heartbeat_timeout_s = 5.0;          // an up module silent this long is killed and restarted
  double backoff_max_s = 5.0;                // restarts of a module that keeps failing back off up to this
  std::vector<std::string> needs;            // files (relative to the root) it reads: checked by --check
  std::vector<std::string> env;              // extra "NAME=value" entries
  bool run_when_closed = false;              // "when_closed": "run": kept running outside the opening hours
};

// Camera frames outside the full-rate windows (modules/logger/README.md, "A day within a disk budget").
struct FrameSpec {
  double rate = 2;    // frames kept per second
  double before_s;    // every frame this long before a moment (red, collapse, round end, mark) ...
  double after_s;     // ... and this long after; both default to the logger's own (LoggerConfig)
  bool answers_with_frames = false;  // "answers": "with_frames": a thinned frame's stacks, predictions ... go too
  double max_mb_per_hour = 0;        // the windows' hourly allowance (recording_policy.h); 0 = none
};

struct LoggerSpec {
  std::string file = "logs/bricklayer-%Y%m%d-%H%M%S";  // strftime pattern, relative to the project root
  int rotate = 10;       // keep FILE.0 .. FILE.<rotate-1>; 0 = increment (default when budget_mb is given)
  double split_mb = 100; // start a new file beyond this size
  double budget_mb = 0;  // every recording of the series together at most; the oldest deleted first; 0 = none
  double min_free_mb = 0;  // free space the logger leaves on the disk, deleting the oldest recordings
  std::optional<FrameSpec> frames;  // thin camera frames; absent = keep every frame
};

// The recordings a budget covers: the file name of the pattern up to its first strftime conversion
// ("logs/demo-%Y%m%d" -> "demo-"), or the whole name and a dot when it has none.
std::string series_prefix(const std::string& file_pattern);
// bricklayer-logger's arguments for the spec (after the program and --lcm-url), ending with the file.
std::vector<std::string> logger_arguments(const LoggerSpec& spec, const std::string& file);

struct Profile {
  std::string name;
  std::string description;
  std::vector<ModuleSpec> modules;           // start order
  std::optional<LoggerSpec> logger;          // lcm-logger, started first and stopped last
  double duration_s = 0;                     // stop by itself after this long; 0 = until Ctrl-C
  double headless_duration_s = 0;            // the default duration when $DISPLAY is unset
  double stop_timeout_s = 5;                 // SIGTERM deadline before SIGKILL
  std::vector<std::string> notes;            // printed once everything is up ("where to look")
  OpeningHours opening_hours;                // outside them the modules are stopped (default: always open)
  int nightly_restart = -1;                  // seconds after local midnight every process is restarted; -1 = never
  // The interface facing the other host on the LAN ("eth0"): the launcher's default --multicast-route, and
  // what launch/setup --install-service passes with CAP_NET_ADMIN for it. "" = this host uses no LAN.
  std::string multicast_route;
};

// Throws ProfileError naming the file and key for unknown keys, missing keys and bad values (the line, for
// opening_hours and nightly_restart).
Profile parse_profile(const std::string& json_text, const std::string& name);
Profile load_profile(const std::string& path);

RestartPolicy parse_restart_policy(const std::string& text);
std::string to_string(RestartPolicy policy);

}  // namespace bricklayer::launcher
