// bricklayer-status's node: the operator's status page.
//
// Subscribes: BL_HOST_STATE (host_state_t, every host's launcher once a second), BL_ROUND (round_t,
//             newest wins), BL_HEARTBEAT (heartbeat_t: each module's own figures for the page).
//             Malformed messages are counted errors.
// Serves:     http://LISTEN:PORT/ (a page that polls /state.json every second), /state.json (the
//             StatusBoard's JSON, with "camera" and "projector": each image's age), /camera.jpg,
//             /projector.jpg and POST /action (operator actions, with the token; operator_actions.h),
//             from the StatusServer's own thread.
// Publishes:  BL_COMMAND (command_t) for every accepted action; BL_HEARTBEAT once a second (status "no
//             host states for N s" when every launcher is silent; values actions_accepted,
//             actions_refused, actions_bad).
#pragma once

#include <memory>
#include <string>

#include "bricklayer/runtime/config.h"
#include "bricklayer/runtime/node.h"
#include "bricklayer/status/operator_actions.h"
#include "bricklayer/status/status_board.h"
#include "bricklayer/status/status_server.h"

namespace bricklayer::status {

struct StatusConfig {
  std::string listen = "127.0.0.1";
  int port = 8080;
  double silent_after_s = kDefaultSilentAfterS;
  std::string token_file = default_token_file();

  template <typename Visitor>
  void visit(Visitor& v) {
    v(runtime::param("listen", listen,
                     "address the page listens on: 127.0.0.1 = this machine only; 0.0.0.0 exposes it to "
                     "every machine on the LAN (actions still need the token)"));
    v(runtime::param("port", port, "TCP port of the page (0 = any free port, printed at start)").range(0, 65535));
    v(runtime::param("silent-after", silent_after_s, "a host not heard from for this long, seconds, is reported silent")
          .range(1.5, 3600));
    v(runtime::param("token-file", token_file,
                     "the operator's token for actions (restart, reset, mark, check calibration, calibrate, condition); no such file = the "
                     "page is read-only. launch/setup writes one readable only by its owner"));
  }
};

class StatusNode final : public runtime::Node {
 public:
  using Config = StatusConfig;
  static constexpr const char* kProgram = "bricklayer-status";
  static constexpr const char* kSummary =
      "The operator's status page: every host's modules (from BL_HOST_STATE) and the round (BL_ROUND),\n"
      "served as a web page at http://LISTEN:PORT/ and as JSON at /state.json; with the operator's token\n"
      "(--token-file) the page also restarts modules, resets the round, marks moments, checks or redoes the calibration and sets the display condition.";

  // Throws std::invalid_argument for a bad configuration, std::runtime_error when it cannot listen.
  StatusNode(const Config& config, runtime::Bus& bus);

  const StatusBoard& board() const { return board_; }
  int port() const { return server_->port(); }
  const StatusServer& server() const { return *server_; }
  const ActionDesk& desk() const { return *desk_; }
  const LatestImage& camera() const { return camera_; }
  const LatestImage& projector() const { return projector_; }

 private:
  void tick() override;
  void before_heartbeat() override;

  StatusBoard board_;
  LatestImage camera_, projector_;
  std::unique_ptr<ActionDesk> desk_;
  std::unique_ptr<StatusServer> server_;
  int64_t commands_sent_ = 0;
};

}  // namespace bricklayer::status
