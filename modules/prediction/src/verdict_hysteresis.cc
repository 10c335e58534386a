#include "bricklayer/prediction/verdict_hysteresis.h"

#include <cmath>
#include <stdexcept>

namespace bricklayer::prediction {

VerdictHysteresis::VerdictHysteresis(double band) : band_(band) {
  if (!(band >= 0.0 && band <= 10.0)) throw std::invalid_argument("hysteresis band must be in [0, 10]");
}

int8_t VerdictHysteresis::update(const prediction_t& p) {
  if (p.status != prediction_t::STATUS_OK) return prediction_t::VERDICT_KNIFE_EDGE;
  const int8_t raw = p.raw_verdict;
  int8_t shown = raw;
  if (raw != prediction_t::VERDICT_KNIFE_EDGE && shown_ == prediction_t::VERDICT_KNIFE_EDGE &&
      std::abs(p.margin) < (1.0 + band_) * p.uncertainty) {
    shown = prediction_t::VERDICT_KNIFE_EDGE;  // proved, but not yet with room to spare
  }
  shown_ = shown;
  return shown;
}

}  // namespace bricklayer::prediction
