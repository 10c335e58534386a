#include "bricklayer/status/status_node.h"

#include <stdexcept>

#include "bricklayer/common/channels.h"
#include "bricklayer/common/log.h"
#include "bricklayer/launcher/supervisor.h"

namespace bricklayer::status {

StatusNode::StatusNode(const Config& config, runtime::Bus& bus)
    : Node("status", bus), board_(config.silent_after_s) {
  if (config.listen.empty()) throw std::invalid_argument("--listen must name an address, e.g. 127.0.0.1");
  const std::string host_states = channel(launcher::kHostStateChannel);
  // Every host's message must reach the board, so a queue, not newest-wins (two hosts, one a second).
  subscribe<host_state_t>(host_states, runtime::QueuePolicy::keep(64),
                          [this](const host_state_t& s) { board_.update(s, now()); });
  subscribe<round_t>(channel(kRoundChannel), runtime::QueuePolicy::newest(), [this](const round_t& r) { board_.update(r); });
  // Each module's own figures (frames per second, latency, calibration age, disk use) for its row.
  subscribe<heartbeat_t>(channel(kHeartbeatChannel), runtime::QueuePolicy::keep(256),
                         [this](const heartbeat_t& hb) { board_.update(hb); });
  // The images: newest wins, the page shows only the latest (a queue would copy 30 JPEGs a second).
  for (auto [name, latest] : {std::pair{kImageChannel, &camera_}, std::pair{kProjectorImageChannel, &projector_}}) {
    const std::string ch = channel(name);
    subscribe<image_t>(ch, runtime::QueuePolicy::newest(), [this, ch, latest](const image_t& im) {
      if (auto why = latest->update(im, now())) error("bad images", ch + ": " + *why);
    });
  }
  watch_input(host_states, config.silent_after_s, "no host states");
  board_.set_now(now());
  desk_ = std::make_unique<ActionDesk>(load_token(config.token_file));
  camera_.set_now(now());
  projector_.set_now(now());
  server_ = std::make_unique<StatusServer>(board_, *desk_, config.listen, config.port, &camera_, &projector_);
  log::info("status page at http://" + config.listen + ":" + std::to_string(server_->port()) + "/" +
            (desk_->enabled() ? " (actions need the token in " + config.token_file + ")"
                              : " (read-only: no token file " + config.token_file + ")"));
}

void StatusNode::tick() {
  board_.set_now(now());
  camera_.set_now(now());
  projector_.set_now(now());
  for (command_t c : desk_->drain()) {
    c.utime = now();
    c.sequence = ++commands_sent_;
    publish(channel(kCommandChannel), c);
  }
}

void StatusNode::before_heartbeat() {
  set_value("hosts", static_cast<double>(board_.num_hosts()));
  set_value("requests", static_cast<double>(server_->requests()));
  set_value("not_found", static_cast<double>(server_->not_found()));
  set_value("actions_accepted", static_cast<double>(desk_->accepted()));
  set_value("actions_refused", static_cast<double>(desk_->refused()));
  set_value("camera_frames", static_cast<double>(camera_.received()));
  set_value("projector_images", static_cast<double>(projector_.received()));
  set_value("actions_bad", static_cast<double>(desk_->bad()));
}

}  // namespace bricklayer::status
