// The camera settings vision needs to hold still: exposure, gain, white balance and focus set from the
// profile and their automatic modes locked, so the board's brightness changes only when the light on
// it does (players' shadows, the projector), never because the camera re-adjusts itself.
//
// apply_controls() reports, per control, what the driver accepted (read back after setting: drivers
// clamp and round). A control the driver lacks is a warning, never a failure: many webcams have no
// focus motor or no separate automatic gain.
#pragma once

#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "bricklayer/frames/v4l2_device.h"
#include "bricklayer/common/flags.h"

namespace bricklayer::frames {

// What the profile asks for; an empty value keeps what the driver has now (locked there when the
// control has an automatic mode).
struct CameraControls {
  std::optional<int32_t> exposure;         // V4L2_CID_EXPOSURE_ABSOLUTE, units of 100 us (100 = 10 ms)
  std::optional<int32_t> gain;             // V4L2_CID_GAIN, driver units
  std::optional<int32_t> white_balance_k;  // V4L2_CID_WHITE_BALANCE_TEMPERATURE, kelvin
  std::optional<int32_t> focus;            // V4L2_CID_FOCUS_ABSOLUTE, driver units
  std::optional<int32_t> power_line_hz;    // V4L2_CID_POWER_LINE_FREQUENCY: 0 (off), 50 or 60
  bool any_value() const { return exposure || gain || white_balance_k || focus; }
  bool all_values() const { return exposure && gain && white_balance_k && focus; }
};

// The flags of bricklayer-camera that carry CameraControls, declared once for the program and for
// readers of a profile (bricklayer-doctor).
void add_control_flags(Flags& flags);
// value_of(name) returns the flag's text, "" when absent. Throws FlagError naming the flag and its range.
CameraControls parse_controls(const std::function<std::string(const std::string&)>& value_of);

enum class ControlOutcome {
  kSet,       // the value asked for, accepted as asked
  kLocked,    // an automatic mode switched off (or found off)
  kKept,      // no value asked for: the driver's current value, reported
  kAbsent,    // the driver has no such control and none was needed (a fixed-focus lens)
  kAdjusted,  // accepted, but the driver chose another value than asked (clamped or rounded): warning
  kMissing,   // asked for or needed, but the driver has no such control: warning
  kRefused,   // the driver returned an error or kept its value: warning
};

struct ControlResult {
  std::string name;  // "auto exposure", "exposure", ...
  ControlOutcome outcome = ControlOutcome::kAbsent;
  std::optional<int32_t> requested;
  std::optional<int32_t> accepted;  // read back from the driver
  std::string detail;
  bool warning() const;
  std::string describe() const;  // one line for the log
};

// Locks the automatic modes first (a manual control is inactive while its automatic mode runs), then
// sets the values asked for, reading every one back.
std::vector<ControlResult> apply_controls(ControlDevice& device, const CameraControls& controls);

// Read-only: for each automatic mode that matters, whether the driver has it, whether it can be
// locked, and whether it is locked now (bricklayer-camera leaves it locked).
struct AutomaticState {
  std::string name;
  bool present = false;
  bool lockable = false;
  bool locked = false;
  bool matters = false;  // exposure and white balance: a camera without the switch may still adjust itself
  std::string detail;
};
std::vector<AutomaticState> inspect_automatic(ControlDevice& device);

// One line per control the driver offers (name, id, range, default, current value, flags), for
// `bricklayer-camera --list-controls` when choosing the profile's values.
std::vector<std::string> describe_controls(ControlDevice& device);

}  // namespace bricklayer::frames
