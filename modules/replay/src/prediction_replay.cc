#include "bricklayer/replay/prediction_replay.h"

#include <cmath>
#include <sstream>

#include "bricklayer/common/channels.h"

namespace bricklayer::replay {
namespace {

std::optional<prediction_t> decode_prediction(const Bytes& bytes) {
  prediction_t p{};
  if (p.decode(bytes.data(), 0, static_cast<int>(bytes.size())) < 0) return std::nullopt;
  return p;
}

template <typename T>
void diff(std::ostringstream& out, int& n, const std::string& what, const T& recorded, const T& replayed) {
  if (recorded == replayed) return;
  if (n++ < 6) out << (n > 1 ? "; " : "") << what << " " << recorded << " (log) vs " << replayed << " (replay)";
}

}  // namespace

PredictionReplay::PredictionReplay(std::string annotator, std::string solver, size_t max_blocks,
                                   std::optional<double> position_tolerance)
    : annotator_fixed_(!annotator.empty()), solver_fixed_(!solver.empty()),
      tolerance_fixed_(position_tolerance.has_value()) {
  if (annotator_fixed_) config_.annotator = annotator;
  if (solver_fixed_) config_.solver = solver;
  if (tolerance_fixed_) config_.position_tolerance = *position_tolerance;
  config_.max_blocks = static_cast<int>(max_blocks);
  prediction::PredictionLogic check(config_);  // reject a bad annotator now
}

std::vector<std::string> PredictionReplay::input_channels() const { return {channel(kStackChannel)}; }
std::vector<std::string> PredictionReplay::output_channels() const { return {channel(kPredictionChannel)}; }

void PredictionReplay::observe_recorded(const std::string&, const Bytes& bytes) {
  if (logic_ || (annotator_fixed_ && solver_fixed_ && tolerance_fixed_)) return;
  auto p = decode_prediction(bytes);
  if (!p || p->status != prediction_t::STATUS_OK) return;
  // Adopt the recorded configuration, so a log made with --annotator paper checks as such. The
  // solver field says what ran ("clp", "clp+nnls"): its LP backend is what the process was given.
  if (!annotator_fixed_) {
    try {
      prediction::PredictionConfig candidate = config_;
      candidate.annotator = p->annotator;
      prediction::PredictionLogic check(candidate);
      config_ = candidate;
      annotator_fixed_ = true;
    } catch (const std::exception&) {
      // an annotator this build does not know: keep the default; mismatches will say so
    }
  }
  if (!tolerance_fixed_) {
    prediction::PredictionConfig candidate = config_;
    candidate.position_tolerance = p->position_tolerance;
    try {
      prediction::PredictionLogic check(candidate);
      config_ = candidate;
      tolerance_fixed_ = true;
    } catch (const std::exception&) {
      // out of range: keep the default; mismatches will say so
    }
  }
  if (!solver_fixed_) {
    if (std::string lp = prediction::lp_backend_of(p->solver); !lp.empty()) {
      config_.solver = lp;
      solver_fixed_ = true;
    }
  }
}

std::optional<std::vector<Output>> PredictionReplay::feed(const std::string& ch, const Bytes& bytes) {
  if (!logic_) logic_.emplace(config_);
  // The same limits as the live process (Module::subscribe with max_stack_message_bytes).
  if (bytes.size() > prediction::max_stack_message_bytes(static_cast<size_t>(config_.max_blocks))) return std::nullopt;
  stack_t s{};
  if (s.decode(bytes.data(), 0, static_cast<int>(bytes.size())) < 0) return std::nullopt;
  prediction_t p = logic_->answer(s);
  Output o;
  o.channel = channel(kPredictionChannel);
  o.bytes.resize(static_cast<size_t>(p.getEncodedSize()));
  if (p.encode(o.bytes.data(), 0, static_cast<int>(o.bytes.size())) < 0)
    throw std::logic_error("prediction_t failed to encode");
  return std::vector<Output>{std::move(o)};
}

std::optional<MessageKey> PredictionReplay::key(const std::string& ch, const Bytes& bytes) const {
  auto p = decode_prediction(bytes);
  if (!p) return std::nullopt;
  return MessageKey{ch, p->utime, p->frame_number};
}

std::string PredictionReplay::describe_difference(const std::string&, const Bytes& recorded_bytes,
                                                  const Bytes& replayed_bytes) const {
  auto a = decode_prediction(recorded_bytes);
  auto b = decode_prediction(replayed_bytes);
  if (!a) return "the recorded message does not decode as prediction_t";
  if (!b) return "the replayed message does not decode as prediction_t";
  std::ostringstream out;
  out.precision(17);
  int n = 0;
  diff(out, n, "status", int(a->status), int(b->status));
  diff(out, n, "error", a->error, b->error);
  diff(out, n, "balanced", a->balanced, b->balanced);
  diff(out, n, "overhang", a->overhang, b->overhang);
  diff(out, n, "score", a->score, b->score);
  diff(out, n, "annotator", a->annotator, b->annotator);
  diff(out, n, "solver", a->solver, b->solver);
  diff(out, n, "position_tolerance", a->position_tolerance, b->position_tolerance);
  diff(out, n, "num_blocks", a->num_blocks, b->num_blocks);
  for (size_t i = 0; i < std::min(a->blocks.size(), b->blocks.size()); ++i) {
    const auto& x = a->blocks[i];
    const auto& y = b->blocks[i];
    std::string at = "block[" + std::to_string(i) + "] ";
    diff(out, n, at + "id", x.id, y.id);
    diff(out, n, at + "state", int(x.state), int(y.state));
    diff(out, n, at + "accel", x.accel, y.accel);
    diff(out, n, at + "alpha", x.alpha, y.alpha);
  }
  if (n == 0) return "bytes differ but every field is equal (NaN or encoding difference)";
  if (n > 6) out << "; ... " << (n - 6) << " more differences";
  return out.str();
}

}  // namespace bricklayer::replay
