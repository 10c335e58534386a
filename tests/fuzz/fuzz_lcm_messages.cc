// Every message type's decoder on arbitrary bytes: the first byte picks the type, the rest is the
// message. Decoders must reject (return < 0) or decode without reading out of bounds or allocating
// more than the message could hold; a decoded message must re-encode within the size it reports
// (less when a string holds a NUL byte: LCM encodes strings up to their first NUL).
#include <cstdint>
#include <vector>

#include "bricklayer/calibration_t.hpp"
#include "bricklayer/collapse_preview_t.hpp"
#include "bricklayer/command_t.hpp"
#include "bricklayer/heartbeat_t.hpp"
#include "bricklayer/hint_t.hpp"
#include "bricklayer/image_t.hpp"
#include "bricklayer/node_config_t.hpp"
#include "bricklayer/prediction_t.hpp"
#include "bricklayer/projector_state_t.hpp"
#include "bricklayer/round_t.hpp"
#include "bricklayer/stack_t.hpp"
#include "bricklayer/study_answer_t.hpp"
#include "bricklayer/study_command_t.hpp"
#include "bricklayer/study_problem_t.hpp"
#include "bricklayer/study_session_t.hpp"
#include "bricklayer/study_trial_t.hpp"
#include "bricklayer/timing_t.hpp"

namespace {
template <typename T>
void roundtrip(const uint8_t* data, size_t size) {
  T msg{};
  if (msg.decode(data, 0, static_cast<int>(size)) < 0) return;
  std::vector<uint8_t> out(static_cast<size_t>(msg.getEncodedSize()));
  int written = msg.encode(out.data(), 0, static_cast<int>(out.size()));
  if (written < 0 || written > static_cast<int>(out.size())) __builtin_trap();
}
}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size < 1 || size > (1 << 20)) return 0;
  const uint8_t* body = data + 1;
  size_t n = size - 1;
  switch (data[0] % 17) {
    case 0: roundtrip<bricklayer::image_t>(body, n); break;
    case 1: roundtrip<bricklayer::stack_t>(body, n); break;
    case 2: roundtrip<bricklayer::prediction_t>(body, n); break;
    case 3: roundtrip<bricklayer::heartbeat_t>(body, n); break;
    case 4: roundtrip<bricklayer::command_t>(body, n); break;
    case 5: roundtrip<bricklayer::calibration_t>(body, n); break;
    case 6: roundtrip<bricklayer::round_t>(body, n); break;
    case 7: roundtrip<bricklayer::projector_state_t>(body, n); break;
    case 8: roundtrip<bricklayer::collapse_preview_t>(body, n); break;
    case 9: roundtrip<bricklayer::hint_t>(body, n); break;
    case 10: roundtrip<bricklayer::timing_t>(body, n); break;
    case 11: roundtrip<bricklayer::node_config_t>(body, n); break;
    case 12: roundtrip<bricklayer::study_session_t>(body, n); break;
    case 13: roundtrip<bricklayer::study_trial_t>(body, n); break;
    case 14: roundtrip<bricklayer::study_problem_t>(body, n); break;
    case 15: roundtrip<bricklayer::study_answer_t>(body, n); break;
    case 16: roundtrip<bricklayer::study_command_t>(body, n); break;
  }
  return 0;
}
