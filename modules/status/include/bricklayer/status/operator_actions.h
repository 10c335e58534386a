// The operator's actions from the status page: start or reset the round, mark a moment in the log,
// check the calibration for drift, calibrate, restart a module, set the display condition. Each is one
// command_t on BL_COMMAND, which the modules already obey (projection the round and the condition, the
// logger the mark, calibrate --serve the self-check and the calibration, the host's launcher the restart).
//
// The page is read-only without a token: an action needs the token in the X-Bricklayer-Token header,
// equal to the contents of the token file launch/setup writes outside the repository
// (~/.config/bricklayer/status-token, readable only by its owner). No token file = no actions at all.
//
// Threads: the HTTP server's thread decides and queues (ActionDesk::take), the node's thread drains the
// queue and publishes (the bus is not thread-safe, and the command's time is the node's bus clock).
#pragma once

#include <cstdint>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "bricklayer/command_t.hpp"

namespace bricklayer::status {

// The default token file: $HOME/.config/bricklayer/status-token ("" when HOME is unset).
std::string default_token_file();

// The token in a file: its first line without surrounding white space. "" when the file is missing or
// empty (actions off). Throws std::runtime_error for a file that exists but cannot be read, or a token
// shorter than 16 characters (a guessable token is worse than none).
std::string load_token(const std::string& path);

// What the server answers an action request with.
struct ActionAnswer {
  int http_status = 200;  // 200 queued, 400 bad request, 403 no or wrong token, 503 actions off
  std::string words;      // for the page, in plain words
  std::optional<command_t> command;  // the command to publish (utime and sequence set by the node)
};

// Decides one request: its body (JSON {"action": ..., "host": ..., "module": ..., "note": ...}) and the
// token it carried. Actions: "start_round", "reset_round", "mark_moment" (note optional),
// "check_calibration" (SELF_CHECK), "calibrate" (CALIBRATE; "step": "scale-from-blocks" for the board
// scale step, argument "scale-from-blocks"), "restart" (host and module required),
// "set_condition" ("condition": "blue",
// "red" or "proposed": command_t SET_CONDITION with index 1, 2, 3). Never throws.
ActionAnswer decide_action(const std::string& body, const std::string& token_given, const std::string& token_expected);

// The actions queued by the server's thread for the node's thread, and the counts the heartbeat shows.
class ActionDesk {
 public:
  static constexpr size_t kMaxQueued = 100;

  explicit ActionDesk(std::string token) : token_(std::move(token)) {}

  bool enabled() const { return !token_.empty(); }
  // Decides, counts and (when accepted) queues. Called from the server's thread.
  ActionAnswer take(const std::string& body, const std::string& token_given);
  // The accepted commands since the last call, oldest first. Called from the node's thread.
  std::vector<command_t> drain();

  int64_t accepted() const;
  int64_t refused() const;  // no token, wrong token, or actions off
  int64_t bad() const;      // malformed requests with the right token

 private:
  const std::string token_;
  mutable std::mutex mutex_;
  std::vector<command_t> queue_;
  int64_t accepted_ = 0, refused_ = 0, bad_ = 0;
};

}  // namespace bricklayer::status
