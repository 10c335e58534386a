#include "bricklayer/study/session_node.h"

#include <stdexcept>

#include "bricklayer/command_t.hpp"
#include "bricklayer/common/channels.h"
#include "bricklayer/study/channels.h"

namespace bricklayer::study {
namespace {

constexpr size_t kStacksKept = 16;  // predictions answer within a frame or two; 16 is ample
constexpr int64_t kLingerUs = 2'000'000;

core::Stack to_stack(const bricklayer::stack_t& msg) {
  core::Stack s;
  s.block_length = msg.block_length;
  s.block_height = msg.block_height;
  s.table_edge = msg.table_edge;
  for (const auto& b : msg.blocks) s.blocks.push_back({b.id, b.row, b.x});
  return s;
}

std::shared_ptr<const StabiliseChecker> stabilise_checker(const std::string& path) {
  try {
    return std::make_shared<const StabiliseChecker>(load_problem(path));
  } catch (const ProblemError& e) {
    throw std::invalid_argument(e.what());
  }
}

}  // namespace

SessionNode::SessionNode(const SessionConfig& config, runtime::Bus& bus)
    : Node("study-session", bus),
      config_(config),
      session_channel_(channel(kSessionChannel)),
      problem_channel_(channel(kProblemChannel)),
      trial_channel_(channel(kTrialChannel)),
      answer_channel_(channel(kAnswerChannel)),
      command_channel_(channel(kCommandChannel)) {
  SessionSetup setup;
  setup.subject_id = config.subject;
  setup.condition = parse_condition(config.condition);  // std::invalid_argument: a bad configuration
  setup.session_id = config.session_id.empty() ? config.subject + "-" + std::to_string(now() / 1'000'000) : config.session_id;
  setup.trial_ms = static_cast<int64_t>(config.trial_seconds * 1000.0);
  setup.clear_ms = static_cast<int64_t>(config.clear_seconds * 1000.0);
  setup.settle_ms = static_cast<int64_t>(config.settle_seconds * 1000.0);
  Problem score;
  try {
    score = load_problem(config.problem_3);
  } catch (const ProblemError& e) {
    throw std::invalid_argument(e.what());
  }
  protocol_ = std::make_unique<SessionProtocol>(setup, stabilise_checker(config.problem_1),
                                                stabilise_checker(config.problem_2), score);
  subscribe<bricklayer::stack_t>(channel(kStackChannel), runtime::QueuePolicy::keep(8),
                                 [this](const bricklayer::stack_t& m) { handle_stack(m); });
  subscribe<bricklayer::prediction_t>(channel(kPredictionChannel), runtime::QueuePolicy::keep(8),
                                      [this](const bricklayer::prediction_t& m) { handle_prediction(m); });
  subscribe<bricklayer::study_command_t>(channel(kStudyCommandChannel), runtime::QueuePolicy::keep(32),
                                         [this](const bricklayer::study_command_t& m) { handle_command(m); });
  watch_input(channel(kPredictionChannel), 5.0, "no predictions");
  set_tick_ms(50);
  if (!config.wait_for_start) {
    send_command(bricklayer::command_t::SET_CONDITION, static_cast<int32_t>(setup.condition));
    protocol_->start(now());
  }
  flush();
}

void SessionNode::handle_stack(const bricklayer::stack_t& msg) {
  stacks_.push_back(msg);
  while (stacks_.size() > kStacksKept) stacks_.pop_front();
}

void SessionNode::handle_prediction(const bricklayer::prediction_t& msg) {
  Observation o;
  o.utime = now();
  o.valid = msg.status == bricklayer::prediction_t::STATUS_OK;
  o.balanced = msg.balanced;
  o.score = msg.score;
  bool paired = false;
  for (auto it = stacks_.rbegin(); it != stacks_.rend(); ++it) {
    if (it->frame_number == msg.frame_number && it->utime == msg.utime) {
      o.stack = to_stack(*it);
      paired = true;
      break;
    }
  }
  if (!paired) {
    // A prediction whose stack was not heard (or dropped) cannot say where the blocks are.
    ++unpaired_;
    count_dropped();
    return;
  }
  ++observations_;
  protocol_->observe(o);
  flush();
}

void SessionNode::handle_command(const bricklayer::study_command_t& msg) {
  if (!msg.session_id.empty() && msg.session_id != protocol_->state(now()).session_id) return;
  if (last_study_sequence_ && msg.sequence == *last_study_sequence_) return;  // the same command again
  last_study_sequence_ = msg.sequence;
  bool applied = false;
  switch (msg.command) {
    case bricklayer::study_command_t::START:
      send_command(bricklayer::command_t::SET_CONDITION, protocol_->state(now()).condition);
      applied = protocol_->start(now());
      break;
    case bricklayer::study_command_t::PAUSE: applied = protocol_->pause(now()); break;
    case bricklayer::study_command_t::RESUME: applied = protocol_->resume(now()); break;
    case bricklayer::study_command_t::REPEAT: applied = protocol_->repeat(now()); break;
    case bricklayer::study_command_t::ABORT: applied = protocol_->abort(now()); break;
    case bricklayer::study_command_t::DONE: applied = protocol_->done(now()); break;
    default: error("bad command", "study command " + std::to_string(msg.command) + " is not one of 1..6"); return;
  }
  if (!applied) warn("command not applicable", "study command " + std::to_string(msg.command) + " does not apply now");
  flush();
}

void SessionNode::send_command(int32_t command, int32_t index) {
  bricklayer::command_t c{};
  c.utime = now();
  c.command = command;
  c.index = index;
  c.sequence = ++command_sequence_;
  publish(command_channel_, c);
}

void SessionNode::flush() {
  SessionOutputs out = protocol_->take_outputs();
  for (RoundCommand r : out.rounds) {
    if (r == RoundCommand::kStart) {
      send_command(bricklayer::command_t::SET_CONDITION, protocol_->state(now()).condition);
      send_command(bricklayer::command_t::START_ROUND, 0);
    } else {
      send_command(bricklayer::command_t::RESET_ROUND, 0);
    }
  }
  for (const auto& t : out.trials) publish(trial_channel_, t);
  for (const auto& a : out.answers) publish(answer_channel_, a);
  for (const auto& p : out.problems) {
    publish(problem_channel_, p);
    last_problem_utime_ = now();
  }
  if (out.state_changed) publish_state();
  if (protocol_->finished() && !finished_utime_) finished_utime_ = now();
}

void SessionNode::publish_state() {
  publish(session_channel_, protocol_->state(now()));
  last_state_utime_ = now();
}

void SessionNode::tick() {
  protocol_->tick(now());
  flush();
  if (now() - last_state_utime_ >= 1'000'000) publish_state();
  if (const auto p = protocol_->current_problem(now());
      p && protocol_->step_state() != bricklayer::study_session_t::STATE_READY && now() - last_problem_utime_ >= 1'000'000) {
    publish(problem_channel_, *p);
    last_problem_utime_ = now();
  }
  if (finished_utime_ && now() - *finished_utime_ >= kLingerUs) stop();
}

void SessionNode::before_heartbeat() {
  set_value("step", protocol_->step());
  set_value("state", protocol_->step_state());
  set_value("observations", static_cast<double>(observations_));
  set_value("unpaired_predictions", static_cast<double>(unpaired_));
}

}  // namespace bricklayer::study
