#include "bricklayer/frames/camera_controls.h"

#include <linux/videodev2.h>

#include <cstdio>
#include <cstring>
#include <sstream>

namespace bricklayer::frames {
namespace {

struct ValueFlag {
  const char* name;
  std::optional<int32_t> CameraControls::*field;
  int32_t min, max;
  const char* help;
};

const ValueFlag kValueFlags[] = {
    {"exposure", &CameraControls::exposure, 1, 100000,
     "camera exposure in units of 100 us (100 = 10 ms; a multiple of 10 ms under 50 Hz lights avoids flicker); "
     "\"\" = lock at what automatic exposure chose"},
    {"gain", &CameraControls::gain, 0, 100000, "camera gain, driver units (see --list-controls); \"\" = lock at the current gain"},
    {"white-balance", &CameraControls::white_balance_k, 1000, 15000,
     "white balance temperature, kelvin; \"\" = lock at what automatic white balance chose"},
    {"focus", &CameraControls::focus, 0, 100000, "absolute focus, driver units; \"\" = lock at what autofocus chose"},
    {"power-line-hz", &CameraControls::power_line_hz, 0, 60,
     "mains frequency for the camera's flicker filter: 50, 60 or 0 (off); \"\" = leave it"},
};

// An automatic mode and the value that switches it off.
struct AutoSpec {
  const char* name;
  uint32_t id;
  int32_t manual;
  bool matters;  // see AutomaticState::matters
  const char* why_absent;
};

const AutoSpec kAutos[] = {
    {"auto exposure", V4L2_CID_EXPOSURE_AUTO, V4L2_EXPOSURE_MANUAL, true,
     "the driver has no automatic exposure switch: if the image still brightens and darkens by itself, use another camera"},
    // On: the camera may lower its frame rate to lengthen the exposure in dim light.
    {"exposure priority", V4L2_CID_EXPOSURE_AUTO_PRIORITY, 0, false, "no exposure priority control"},
    {"auto gain", V4L2_CID_AUTOGAIN, 0, false, "no separate automatic gain (it follows automatic exposure)"},
    {"auto white balance", V4L2_CID_AUTO_WHITE_BALANCE, 0, true,
     "the driver has no automatic white balance switch: if colours drift by themselves, use another camera"},
    {"auto focus", V4L2_CID_FOCUS_AUTO, 0, false, "no autofocus (a fixed-focus lens)"},
};

struct ManualSpec {
  const char* name;
  uint32_t id;
  uint32_t fallback_id;  // a driver without the absolute control may have the plain one
  std::optional<int32_t> CameraControls::*field;
};

const ManualSpec kManuals[] = {
    {"exposure", V4L2_CID_EXPOSURE_ABSOLUTE, V4L2_CID_EXPOSURE, &CameraControls::exposure},
    {"gain", V4L2_CID_GAIN, 0, &CameraControls::gain},
    {"white balance", V4L2_CID_WHITE_BALANCE_TEMPERATURE, 0, &CameraControls::white_balance_k},
    {"focus", V4L2_CID_FOCUS_ABSOLUTE, 0, &CameraControls::focus},
};

std::string error_text(int e) { return std::strerror(e); }

ControlResult lock_automatic(ControlDevice& device, const AutoSpec& spec) {
  ControlResult r;
  r.name = spec.name;
  r.requested = spec.manual;
  std::optional<ControlInfo> info = device.query(spec.id);
  if (!info) {
    r.outcome = spec.matters ? ControlOutcome::kMissing : ControlOutcome::kAbsent;
    r.detail = spec.why_absent;
    return r;
  }
  if (info->read_only()) {
    r.outcome = ControlOutcome::kRefused;
    r.detail = "read-only: the driver does not let it be switched off";
    return r;
  }
  if (!info->menu.empty() && !info->offers(spec.manual)) {
    r.outcome = ControlOutcome::kRefused;
    r.detail = "the driver offers no manual mode";
    return r;
  }
  int32_t now = 0;
  if (device.get(spec.id, now) == 0 && now == spec.manual) {
    r.outcome = ControlOutcome::kLocked;
    r.accepted = now;
    r.detail = "was already off";
    return r;
  }
  if (int e = device.set(spec.id, spec.manual); e != 0) {
    r.outcome = ControlOutcome::kRefused;
    r.detail = "the driver refused to switch it off: " + error_text(e);
    return r;
  }
  if (int e = device.get(spec.id, now); e != 0) {
    r.outcome = ControlOutcome::kRefused;
    r.detail = "cannot read it back: " + error_text(e);
    return r;
  }
  r.accepted = now;
  r.outcome = now == spec.manual ? ControlOutcome::kLocked : ControlOutcome::kRefused;
  if (now != spec.manual) r.detail = "the driver kept " + std::to_string(now);
  return r;
}

ControlResult set_value(ControlDevice& device, const char* name, uint32_t id, uint32_t fallback_id,
                        std::optional<int32_t> requested, const char* absent_note) {
  ControlResult r;
  r.name = name;
  r.requested = requested;
  std::optional<ControlInfo> info = device.query(id);
  if (!info && fallback_id != 0) {
    id = fallback_id;
    info = device.query(id);
  }
  if (!info) {
    r.outcome = requested ? ControlOutcome::kMissing : ControlOutcome::kAbsent;
    r.detail = requested ? "the driver has no such control: the value is ignored" : absent_note;
    return r;
  }
  const std::string range = "range " + std::to_string(info->minimum) + ".." + std::to_string(info->maximum);
  int32_t now = 0;
  if (!requested) {
    if (int e = device.get(id, now); e != 0) {
      r.outcome = ControlOutcome::kRefused;
      r.detail = "cannot read it: " + error_text(e);
      return r;
    }
    r.outcome = ControlOutcome::kKept;
    r.accepted = now;
    r.detail = "kept (" + range + ")";
    return r;
  }
  if (info->read_only()) {
    r.outcome = ControlOutcome::kRefused;
    r.detail = "read-only";
    return r;
  }
  if (int e = device.set(id, *requested); e != 0) {
    r.outcome = ControlOutcome::kRefused;
    r.detail = "the driver refused " + std::to_string(*requested) + ": " + error_text(e) +
               (info->inactive() ? " (inactive: its automatic mode is still on)" : "") + " (" + range + ")";
    if (device.get(id, now) == 0) r.accepted = now;
    return r;
  }
  if (int e = device.get(id, now); e != 0) {
    r.outcome = ControlOutcome::kRefused;
    r.detail = "cannot read it back: " + error_text(e);
    return r;
  }
  r.accepted = now;
  if (now == *requested) {
    r.outcome = ControlOutcome::kSet;
  } else {
    r.outcome = ControlOutcome::kAdjusted;
    r.detail = "asked " + std::to_string(*requested) + ", the driver chose " + std::to_string(now) + " (" + range +
               ", step " + std::to_string(info->step) + ")";
  }
  return r;
}

ControlResult set_power_line(ControlDevice& device, std::optional<int32_t> hz) {
  ControlResult r;
  r.name = "power line";
  r.requested = hz;
  std::optional<ControlInfo> info = device.query(V4L2_CID_POWER_LINE_FREQUENCY);
  if (!info) {
    r.outcome = hz ? ControlOutcome::kMissing : ControlOutcome::kAbsent;
    r.detail = "the driver has no flicker filter";
    return r;
  }
  int32_t now = 0;
  if (!hz) {
    r.outcome = device.get(info->id, now) == 0 ? ControlOutcome::kKept : ControlOutcome::kRefused;
    if (r.outcome == ControlOutcome::kKept) r.accepted = now;
    r.detail = "menu index kept (0 off, 1 50 Hz, 2 60 Hz, 3 auto)";
    return r;
  }
  const int32_t index = *hz == 50 ? V4L2_CID_POWER_LINE_FREQUENCY_50HZ
                        : *hz == 60 ? V4L2_CID_POWER_LINE_FREQUENCY_60HZ
                                    : V4L2_CID_POWER_LINE_FREQUENCY_DISABLED;
  if (!info->offers(index)) {
    r.outcome = ControlOutcome::kRefused;
    r.detail = "the driver offers no " + (*hz ? std::to_string(*hz) + " Hz" : std::string("off")) + " setting";
    return r;
  }
  if (int e = device.set(info->id, index); e != 0) {
    r.outcome = ControlOutcome::kRefused;
    r.detail = "the driver refused it: " + error_text(e);
    return r;
  }
  if (device.get(info->id, now) == 0 && now == index) {
    r.outcome = ControlOutcome::kSet;
    r.accepted = *hz;
  } else {
    r.outcome = ControlOutcome::kRefused;
    r.detail = "the driver kept menu index " + std::to_string(now);
  }
  return r;
}

const char* outcome_name(ControlOutcome o) {
  switch (o) {
    case ControlOutcome::kSet: return "set";
    case ControlOutcome::kLocked: return "locked";
    case ControlOutcome::kKept: return "kept";
    case ControlOutcome::kAbsent: return "absent";
    case ControlOutcome::kAdjusted: return "adjusted";
    case ControlOutcome::kMissing: return "missing";
    case ControlOutcome::kRefused: return "refused";
  }
  return "?";
}

const char* type_name(uint32_t type) {
  switch (type) {
    case V4L2_CTRL_TYPE_INTEGER: return "int";
    case V4L2_CTRL_TYPE_BOOLEAN: return "bool";
    case V4L2_CTRL_TYPE_MENU: return "menu";
    case V4L2_CTRL_TYPE_INTEGER_MENU: return "intmenu";
    case V4L2_CTRL_TYPE_BUTTON: return "button";
    case V4L2_CTRL_TYPE_INTEGER64: return "int64";
    default: return "other";
  }
}

}  // namespace

void add_control_flags(Flags& flags) {
  for (const ValueFlag& f : kValueFlags) flags.add(f.name, "", f.help);
}

CameraControls parse_controls(const std::function<std::string(const std::string&)>& value_of) {
  CameraControls c;
  for (const ValueFlag& f : kValueFlags) {
    const std::string text = value_of(f.name);
    if (text.empty()) continue;
    long long v = 0;
    size_t used = 0;
    try {
      v = std::stoll(text, &used);
    } catch (const std::exception&) {
      used = 0;
    }
    if (used != text.size() || v < f.min || v > f.max)
      throw FlagError("--" + std::string(f.name) + " must be an integer in " + std::to_string(f.min) + ".." +
                      std::to_string(f.max) + " (got '" + text + "')");
    if (std::string(f.name) == "power-line-hz" && v != 0 && v != 50 && v != 60)
      throw FlagError("--power-line-hz must be 50, 60 or 0 (got '" + text + "')");
    c.*(f.field) = static_cast<int32_t>(v);
  }
  return c;
}

bool ControlResult::warning() const {
  return outcome == ControlOutcome::kAdjusted || outcome == ControlOutcome::kMissing || outcome == ControlOutcome::kRefused;
}

std::string ControlResult::describe() const {
  std::ostringstream out;
  out << name << ": " << outcome_name(outcome);
  if (accepted) out << " at " << *accepted;
  if (requested && outcome != ControlOutcome::kLocked && outcome != ControlOutcome::kSet) out << " (asked " << *requested << ")";
  if (!detail.empty()) out << ": " << detail;
  return out.str();
}

std::vector<ControlResult> apply_controls(ControlDevice& device, const CameraControls& controls) {
  std::vector<ControlResult> results;
  results.push_back(set_power_line(device, controls.power_line_hz));
  for (const AutoSpec& spec : kAutos) results.push_back(lock_automatic(device, spec));
  for (const ManualSpec& spec : kManuals)
    results.push_back(set_value(device, spec.name, spec.id, spec.fallback_id, controls.*(spec.field),
                                spec.id == V4L2_CID_FOCUS_ABSOLUTE ? "no focus control (a fixed-focus lens)" : "no such control"));
  return results;
}

std::vector<AutomaticState> inspect_automatic(ControlDevice& device) {
  std::vector<AutomaticState> out;
  for (const AutoSpec& spec : kAutos) {
    if (spec.id == V4L2_CID_EXPOSURE_AUTO_PRIORITY) continue;  // frame rate, not brightness: the camera check measures it
    AutomaticState s;
    s.name = spec.name;
    s.matters = spec.matters;
    std::optional<ControlInfo> info = device.query(spec.id);
    if (!info) {
      s.detail = spec.why_absent;
      out.push_back(s);
      continue;
    }
    s.present = true;
    s.lockable = !info->read_only() && (info->menu.empty() || info->offers(spec.manual));
    int32_t now = 0;
    if (int e = device.get(spec.id, now); e != 0) {
      s.detail = "cannot read it: " + error_text(e);
    } else {
      s.locked = now == spec.manual;
      s.detail = s.locked ? "locked" : (s.lockable ? "on (bricklayer-camera locks it when it starts)" : "on and cannot be switched off");
    }
    out.push_back(s);
  }
  return out;
}

std::vector<std::string> describe_controls(ControlDevice& device) {
  std::vector<std::string> lines;
  for (const ControlInfo& info : device.list()) {
    char id[16];
    std::snprintf(id, sizeof(id), "0x%08x", info.id);
    std::ostringstream line;
    line << info.name << " [" << id << "] " << type_name(info.type) << " " << info.minimum << ".." << info.maximum;
    if (info.step != 1) line << " step " << info.step;
    line << " default " << info.default_value;
    int32_t now = 0;
    if (device.get(info.id, now) == 0) line << " now " << now;
    if (!info.menu.empty()) {
      line << " menu";
      for (int64_t m : info.menu) line << " " << m;
    }
    if (info.inactive()) line << " (inactive)";
    if (info.read_only()) line << " (read-only)";
    lines.push_back(line.str());
  }
  return lines;
}

}  // namespace bricklayer::frames
