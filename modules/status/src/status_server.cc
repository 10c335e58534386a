#include "bricklayer/status/status_server.h"

#include <httplib.h>
#include <sys/socket.h>

#include <chrono>
#include <stdexcept>

#include "bricklayer/status/status_page.h"

namespace bricklayer::status {

StatusServer::StatusServer(const StatusBoard& board, ActionDesk& desk, const std::string& listen, int port,
                           LatestImage* camera, LatestImage* projector)
    : board_(board), desk_(desk), camera_(camera), projector_(projector), server_(std::make_unique<httplib::Server>()) {
  server_->Get("/", [this](const httplib::Request&, httplib::Response& res) {
    ++requests_;
    res.set_content(status_page_html(), "text/html; charset=utf-8");
  });
  server_->Get("/state.json", [this](const httplib::Request&, httplib::Response& res) {
    ++requests_;
    res.set_header("Cache-Control", "no-store");
    nlohmann::json state = board_.to_json();
    state["actions"] = desk_.enabled();
    state["camera"] = camera_ ? camera_->to_json() : nlohmann::json{{"seen", false}};
    state["projector"] = projector_ ? projector_->to_json() : nlohmann::json{{"seen", false}};
    res.set_content(state.dump(), "application/json");
  });
  // The images: the bytes as they came (or one JPEG a second of a raw frame); never cached, the page
  // asks again every few seconds for the newest.
  auto image = [this](LatestImage* latest, const char* what) {
    return [this, latest, what](const httplib::Request&, httplib::Response& res) {
      ++requests_;
      res.set_header("Cache-Control", "no-store");
      const std::optional<ServedImage> im = latest ? latest->get() : std::nullopt;
      if (!im) {
        res.status = 404;
        res.set_content(std::string("no ") + what + " seen yet", "text/plain; charset=utf-8");
        return;
      }
      res.set_content(im->bytes, im->content_type);
    };
  };
  server_->Get("/camera.jpg", image(camera_, "camera frame (nothing on the camera channel)"));
  server_->Get("/projector.jpg", image(projector_, "projector image (projection publishes one every 2 s)"));
  server_->Post("/action", [this](const httplib::Request& req, httplib::Response& res) {
    ++requests_;
    const ActionAnswer a = desk_.take(req.body, req.get_header_value("X-Bricklayer-Token"));
    res.status = a.http_status;
    res.set_header("Cache-Control", "no-store");
    res.set_content(nlohmann::json{{"ok", a.command.has_value()}, {"words", a.words}}.dump(), "application/json");
  });
  server_->set_payload_max_length(64 * 1024);  // an action is a few bytes of JSON
  server_->set_error_handler([this](const httplib::Request&, httplib::Response& res) {
    if (res.status == 404) ++not_found_;
  });
  // httplib's default also sets SO_REUSEPORT, which lets a second status page share the port in
  // silence (the kernel would split the requests between them): only SO_REUSEADDR, so a restart
  // rebinds at once but a port in use is refused.
  server_->set_socket_options([](socket_t sock) {
    int yes = 1;
    ::setsockopt(sock, SOL_SOCKET, SO_REUSEADDR, &yes, sizeof(yes));
  });
  if (port == 0) {
    port_ = server_->bind_to_any_port(listen);
    if (port_ < 0) throw std::runtime_error("cannot listen on " + listen + " (any port)");
  } else {
    if (!server_->bind_to_port(listen, port))
      throw std::runtime_error("cannot listen on " + listen + ":" + std::to_string(port) +
                               " (the port is in use, or the address is not this machine's)");
    port_ = port;
  }
  thread_ = std::thread([this] {
    server_->listen_after_bind();
    serving_done_ = true;
  });
}

StatusServer::~StatusServer() {
  // httplib's stop() does nothing before the server thread has started listening, and the thread would
  // then listen forever: a server destroyed right after it was built waits for its thread to begin.
  while (!server_->is_running() && !serving_done_) std::this_thread::sleep_for(std::chrono::milliseconds(1));
  server_->stop();
  if (thread_.joinable()) thread_.join();
}

}  // namespace bricklayer::status
