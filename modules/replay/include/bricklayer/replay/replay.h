// Deterministic replay of a recorded LCM log through a module's logic, in-process (no network, as
// fast as possible). Every input message of the module is fed in log order; with check, every output
// is compared byte for byte with the output recorded in the log for the same input, matched by
// channel + utime + frame_number (every Bricklayer output carries the utime and frame number of the
// input it answers). Timings live on BL_TIMING and are never compared.
#pragma once

#include <cstdint>
#include <optional>
#include <ostream>
#include <string>
#include <tuple>
#include <vector>

namespace bricklayer::replay {

using Bytes = std::vector<uint8_t>;

struct Output {
  std::string channel;
  Bytes bytes;
};

// Identifies an output by the input it answers.
struct MessageKey {
  std::string channel;
  int64_t utime = 0;
  int64_t frame_number = 0;
  bool operator<(const MessageKey& o) const {
    return std::tie(channel, utime, frame_number) < std::tie(o.channel, o.utime, o.frame_number);
  }
};

// One module's logic behind a replay. Implementations decode, compute and encode exactly like the
// live process (same size limits, same newest-input rule does not apply: every input is fed).
class ReplayModule {
 public:
  virtual ~ReplayModule() = default;
  virtual std::string name() const = 0;
  virtual std::vector<std::string> input_channels() const = 0;
  virtual std::vector<std::string> output_channels() const = 0;
  // Sees every recorded output before any input is fed (e.g. to adopt the recorded configuration).
  virtual void observe_recorded(const std::string& channel, const Bytes& bytes) {}
  // Computes the outputs for one recorded input; nullopt when the input is rejected (malformed,
  // oversized), as the live process would count an error.
  virtual std::optional<std::vector<Output>> feed(const std::string& channel, const Bytes& bytes) = 0;
  // The key of an output message; nullopt when the bytes do not decode.
  virtual std::optional<MessageKey> key(const std::string& channel, const Bytes& bytes) const = 0;
  // A one-line, field-level account of how two outputs differ.
  virtual std::string describe_difference(const std::string& channel, const Bytes& recorded,
                                          const Bytes& replayed) const = 0;
};

struct ReplayReport {
  int64_t events = 0;          // events read from the log (all channels)
  int64_t inputs = 0;          // input messages fed
  int64_t rejected_inputs = 0; // inputs the logic rejected (malformed, oversized)
  int64_t outputs = 0;         // outputs computed
  int64_t compared = 0;        // outputs that had a recorded counterpart
  int64_t mismatches = 0;      // ... and differed (or a recorded output did not decode)
  int64_t not_in_log = 0;      // computed outputs with no recorded counterpart (input dropped live: newest wins)
  int64_t orphans = 0;         // recorded outputs whose input is not in the log (e.g. a log split boundary)
  bool ok() const { return mismatches == 0; }
  std::string summary() const;  // "N compared, M mismatches (...)"
};

// Replays path through module. Prints each mismatch (and, when check is false, nothing per message)
// to out. Throws std::runtime_error when the log cannot be read.
ReplayReport replay_log(const std::string& path, ReplayModule& module, bool check, std::ostream& out);

}  // namespace bricklayer::replay
