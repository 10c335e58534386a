// Any Bricklayer message, compared field by field: decoded from the .lcm definitions compiled into the
// program (bricklayer::inspect's generic decoder), so every module's outputs are compared by one piece
// of code and a difference is named by its field ("blocks[3].state: 2 (log) vs 0 (replay)").
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace bricklayer::replay {

// Which input an output answers: our outputs carry the utime (and most the frame_number) of the input
// they answer (DESIGN.md), so a replayed output is matched with the recorded one by these.
struct MessageKey {
  std::string channel;
  int64_t utime = 0;
  int64_t frame_number = -1;  // -1 for types without one
  bool operator<(const MessageKey& o) const;
  bool operator==(const MessageKey& o) const;
};

struct FieldDifference {
  std::string path;  // "blocks[3].state"
  std::string a, b;  // the values as text
};

class MessageDiff {
 public:
  // ignored: field paths left out of every comparison, with [] for any index ("prediction_t.blocks[].accel")
  // or a whole type ("timing_t").
  explicit MessageDiff(std::vector<std::string> ignored = {});

  // Encoded pictures (an image_t anywhere in a message) whose bytes differ are compared decoded: PNG
  // pixel for pixel, JPEG within this many levels per channel (another encoder build's rounding).
  static constexpr int kJpegTolerance = 2;

  // The message's type name ("prediction_t"), "" when the bytes are no known type.
  std::string type_of(const uint8_t* data, size_t size) const;
  // utime (first member) and frame_number (when the type has it); nullopt when the bytes do not decode.
  std::optional<MessageKey> key(const std::string& channel, const uint8_t* data, size_t size) const;
  // The fields that differ, ignored ones left out (empty: equal as far as compared). A message that
  // does not decode is one difference at path "".
  std::vector<FieldDifference> differences(const std::vector<uint8_t>& a, const std::vector<uint8_t>& b) const;
  // Whether a whole type is ignored.
  bool ignores_type(const std::string& type) const;
  const std::vector<std::string>& ignored() const { return ignored_; }

  // "blocks[3].state: 2 (log) vs 0 (replay); score: 131 vs 130" (at most max fields, then "+N more").
  static std::string describe(const std::vector<FieldDifference>& d, const std::string& a_name,
                              const std::string& b_name, size_t max = 6);

 private:
  bool ignored_path(const std::string& type, const std::string& path) const;
  std::vector<std::string> ignored_;
};

}  // namespace bricklayer::replay
