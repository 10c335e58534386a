#include "bricklayer/status/operator_actions.h"

#include <cstdlib>
#include <fstream>
#include <stdexcept>
#include <system_error>
#include <filesystem>

#include <nlohmann/json.hpp>

#include "bricklayer/study_session_t.hpp"

namespace bricklayer::status {

namespace {

std::string trim(const std::string& s) {
  const auto first = s.find_first_not_of(" \t\r\n");
  if (first == std::string::npos) return "";
  const auto last = s.find_last_not_of(" \t\r\n");
  return s.substr(first, last - first + 1);
}

// Compares without stopping at the first difference, so the answer's timing does not tell how much of
// a guess was right.
bool same_token(const std::string& a, const std::string& b) {
  unsigned char diff = a.size() == b.size() ? 0 : 1;
  const std::string& longer = a.size() >= b.size() ? a : b;
  for (size_t i = 0; i < longer.size(); ++i) {
    const unsigned char x = i < a.size() ? static_cast<unsigned char>(a[i]) : 0;
    const unsigned char y = i < b.size() ? static_cast<unsigned char>(b[i]) : 0;
    diff |= static_cast<unsigned char>(x ^ y);
  }
  return diff == 0;
}

command_t command(int32_t code, const std::string& argument = "") {
  command_t c{};
  c.command = code;
  c.argument = argument;
  c.sequence = -1;
  return c;
}

// A module or host name as the launcher's profile spells it: no '/', no control characters.
bool plain_name(const std::string& s) {
  if (s.empty() || s.size() > 64) return false;
  for (char ch : s)
    if (ch == '/' || static_cast<unsigned char>(ch) < 0x20) return false;
  return true;
}

}  // namespace

std::string default_token_file() {
  const char* home = std::getenv("HOME");
  if (!home || !*home) return "";
  return std::string(home) + "/.config/bricklayer/status-token";
}

std::string load_token(const std::string& path) {
  if (path.empty()) return "";
  std::error_code ec;
  if (!std::filesystem::exists(path, ec)) return "";
  std::ifstream in(path);
  if (!in) throw std::runtime_error("cannot read the token file " + path);
  std::string line;
  std::getline(in, line);
  const std::string token = trim(line);
  if (token.empty()) return "";
  if (token.size() < 16)
    throw std::runtime_error("the token in " + path + " is " + std::to_string(token.size()) +
                             " characters long; use at least 16 (launch/setup writes a random one of 32)");
  return token;
}

ActionAnswer decide_action(const std::string& body, const std::string& token_given, const std::string& token_expected) {
  ActionAnswer a;
  if (token_expected.empty()) {
    a.http_status = 503;
    a.words = "actions are off on this machine: there is no token file (launch/setup writes one)";
    return a;
  }
  if (token_given.empty() || !same_token(token_given, token_expected)) {
    a.http_status = 403;
    a.words = token_given.empty() ? "this action needs the operator's token" : "wrong token: nothing was done";
    return a;
  }
  a.http_status = 400;
  nlohmann::json j;
  try {
    j = nlohmann::json::parse(body);
  } catch (const std::exception&) {
    a.words = "the request is not JSON";
    return a;
  }
  if (!j.is_object() || !j.contains("action") || !j["action"].is_string()) {
    a.words = "the request names no action";
    return a;
  }
  auto text = [&](const char* key) -> std::string {
    return j.contains(key) && j[key].is_string() ? j[key].get<std::string>() : std::string();
  };
  const std::string action = j["action"].get<std::string>();
  a.http_status = 200;
  if (action == "start_round") {
    a.command = command(command_t::START_ROUND);
    a.words = "a new round starts";
  } else if (action == "reset_round") {
    a.command = command(command_t::RESET_ROUND);
    a.words = "the round is reset";
  } else if (action == "mark_moment") {
    std::string note = text("note");
    if (note.size() > 200) note.resize(200);
    a.command = command(command_t::MARK_MOMENT, note.empty() ? "marked on the status page" : note);
    a.words = "the moment is marked in the recording";
  } else if (action == "check_calibration") {
    a.command = command(command_t::SELF_CHECK);
    a.words = "the calibration is checked for drift as soon as the board is empty";
  } else if (action == "calibrate") {
    // "step": "scale-from-blocks" is calibrate's board-scale step (blocks on the bottom row are the ruler);
    // no step is the full calibration. The argument is calibrate's CalibrateNode::kScaleFromBlocks.
    const std::string step = text("step");
    if (!step.empty() && step != "scale-from-blocks") {
      a.http_status = 400;
      a.words = "a calibration's step is scale-from-blocks or none, not '" + step.substr(0, 40) + "'";
      return a;
    }
    a.command = command(command_t::CALIBRATE, step);
    a.words = step.empty() ? "the calibration starts once the board has been empty for a few seconds; the projector "
                             "shows its patterns meanwhile (see Calibration)"
                           : "the board scale is measured from the blocks on the bottom row now (see Calibration)";
  } else if (action == "set_condition") {
    // The display condition of the next round (what the blocks' colours mean), as projection reads
    // command_t.index: study_session_t::CONDITION_BLUE, _RED, _PROPOSED.
    const std::string condition = text("condition");
    const int32_t index = condition == "blue"       ? study_session_t::CONDITION_BLUE
                          : condition == "red"      ? study_session_t::CONDITION_RED
                          : condition == "proposed" ? study_session_t::CONDITION_PROPOSED
                                                    : study_session_t::CONDITION_UNKNOWN;
    if (index == study_session_t::CONDITION_UNKNOWN) {
      a.http_status = 400;
      a.words = "the display condition is blue, red or proposed, not '" + condition.substr(0, 40) + "'";
      return a;
    }
    a.command = command(command_t::SET_CONDITION);
    a.command->index = index;
    a.words = "the display condition is " + condition + " from now on";
  } else if (action == "restart") {
    const std::string host = text("host"), module = text("module");
    if (!plain_name(host) || !plain_name(module)) {
      a.http_status = 400;
      a.words = "a restart needs the host and the module, as the page lists them";
      return a;
    }
    a.command = command(command_t::RESTART_MODULE, host + "/" + module);
    a.words = module + " on " + host + " is restarted";
  } else {
    a.http_status = 400;
    a.words = "no such action: " + action.substr(0, 40);
  }
  return a;
}

ActionAnswer ActionDesk::take(const std::string& body, const std::string& token_given) {
  ActionAnswer a = decide_action(body, token_given, token_);
  std::lock_guard lock(mutex_);
  // The node drains every tick; a full queue means its thread is stuck, and piling up more helps nobody.
  if (a.command && queue_.size() >= kMaxQueued) {
    a.command.reset();
    a.http_status = 503;
    a.words = "the status program is busy: too many actions waiting, try again";
  }
  if (a.command) {
    ++accepted_;
    queue_.push_back(*a.command);
  } else if (a.http_status == 400) {
    ++bad_;
  } else {
    ++refused_;
  }
  return a;
}

std::vector<command_t> ActionDesk::drain() {
  std::lock_guard lock(mutex_);
  std::vector<command_t> out;
  out.swap(queue_);
  return out;
}

int64_t ActionDesk::accepted() const {
  std::lock_guard lock(mutex_);
  return accepted_;
}
int64_t ActionDesk::refused() const {
  std::lock_guard lock(mutex_);
  return refused_;
}
int64_t ActionDesk::bad() const {
  std::lock_guard lock(mutex_);
  return bad_;
}

}  // namespace bricklayer::status
