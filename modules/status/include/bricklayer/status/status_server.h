// The status page's HTTP server (cpp-httplib): GET / (the page), GET /state.json (the board's JSON),
// GET /camera.jpg and /projector.jpg (the latest camera frame and projector image, latest_image.h; 404
// before the first), POST /action (an operator action with the token in the X-Bricklayer-Token header; operator_actions.h).
// It runs in a thread of its own so a slow phone on the museum's Wi-Fi never holds up the node's bus
// loop; it only reads the board and hands actions to the desk, both of which guard themselves with a
// mutex (status_board.h, operator_actions.h).
#pragma once

#include <atomic>
#include <cstdint>
#include <memory>
#include <string>
#include <thread>

#include "bricklayer/status/latest_image.h"
#include "bricklayer/status/operator_actions.h"
#include "bricklayer/status/status_board.h"

namespace httplib {
class Server;
}

namespace bricklayer::status {

class StatusServer {
 public:
  // Binds listen:port at once (port 0: any free port, see port()) and serves from a new thread.
  // Throws std::runtime_error when the address cannot be bound (in use, not this machine's).
  // camera and projector may be null (no image endpoints' content: 404).
  StatusServer(const StatusBoard& board, ActionDesk& desk, const std::string& listen, int port,
               LatestImage* camera = nullptr, LatestImage* projector = nullptr);
  ~StatusServer();  // stops the server and joins its thread
  StatusServer(const StatusServer&) = delete;
  StatusServer& operator=(const StatusServer&) = delete;

  int port() const { return port_; }
  int64_t requests() const { return requests_.load(); }
  int64_t not_found() const { return not_found_.load(); }

 private:
  const StatusBoard& board_;
  ActionDesk& desk_;
  LatestImage* camera_;
  LatestImage* projector_;
  std::unique_ptr<httplib::Server> server_;
  int port_ = 0;
  std::atomic<int64_t> requests_{0}, not_found_{0};
  std::atomic<bool> serving_done_{false};  // the server thread's listen has returned
  std::thread thread_;
};

}  // namespace bricklayer::status
