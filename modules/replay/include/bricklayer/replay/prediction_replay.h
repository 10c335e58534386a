// bricklayer-prediction's logic behind a replay: BL_STACK in, BL_PREDICTION out.
#pragma once

#include <optional>

#include "bricklayer/prediction/prediction_logic.h"
#include "bricklayer/replay/replay.h"

namespace bricklayer::replay {

class PredictionReplay : public ReplayModule {
 public:
  // annotator/solver: "" = adopt what the recorded predictions say (else the process defaults); the same for
  // position_tolerance when not given (so a log re-judged with another tolerance is a choice, not an accident).
  PredictionReplay(std::string annotator, std::string solver, size_t max_blocks,
                   std::optional<double> position_tolerance = std::nullopt);

  std::string name() const override { return "prediction"; }
  std::vector<std::string> input_channels() const override;
  std::vector<std::string> output_channels() const override;
  void observe_recorded(const std::string& channel, const Bytes& bytes) override;
  std::optional<std::vector<Output>> feed(const std::string& channel, const Bytes& bytes) override;
  std::optional<MessageKey> key(const std::string& channel, const Bytes& bytes) const override;
  std::string describe_difference(const std::string& channel, const Bytes& recorded,
                                  const Bytes& replayed) const override;

  // The configuration in use (after observe_recorded); valid once the first input was fed.
  const prediction::PredictionConfig& config() const { return config_; }

 private:
  prediction::PredictionConfig config_;
  bool annotator_fixed_, solver_fixed_, tolerance_fixed_;
  std::optional<prediction::PredictionLogic> logic_;
};

}  // namespace bricklayer::replay
