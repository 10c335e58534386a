// A control device that behaves like the kernel's V4L2 control framework and the UVC driver, for
// tests on machines without a camera (the kernel cannot be reached without one): integer values
// are clamped to the range and rounded to the step, menu indices the driver does not offer are
// EINVAL, read-only controls EACCES, and a manual control is inactive (writes refused with EACCES)
// while its automatic mode is on.
#pragma once

#include <linux/videodev2.h>

#include <algorithm>
#include <cerrno>
#include <map>
#include <optional>
#include <vector>

#include "bricklayer/frames/v4l2_device.h"

namespace bricklayer::test {

class FakeControlDevice final : public frames::ControlDevice {
 public:
  struct Control {
    frames::ControlInfo info;
    int32_t value = 0;
  };

  void add_int(uint32_t id, const char* name, int64_t min, int64_t max, int64_t step, int32_t value) {
    Control c;
    c.info.id = id;
    c.info.name = name;
    c.info.type = V4L2_CTRL_TYPE_INTEGER;
    c.info.minimum = min;
    c.info.maximum = max;
    c.info.step = step;
    c.info.default_value = value;
    c.value = value;
    controls_[id] = c;
    order_.push_back(id);
    update_inactive();
  }
  void add_bool(uint32_t id, const char* name, bool value) {
    add_int(id, name, 0, 1, 1, value ? 1 : 0);
    controls_[id].info.type = V4L2_CTRL_TYPE_BOOLEAN;
  }
  void add_menu(uint32_t id, const char* name, std::vector<int64_t> offered, int32_t value) {
    add_int(id, name, offered.front(), offered.back(), 1, value);
    controls_[id].info.type = V4L2_CTRL_TYPE_MENU;
    controls_[id].info.menu = std::move(offered);
  }
  void make_read_only(uint32_t id) { controls_[id].info.flags |= V4L2_CTRL_FLAG_READ_ONLY; }
  // A driver that accepts a write and keeps its own value (some cameras ignore a switch silently).
  void ignore_writes(uint32_t id) { ignored_.push_back(id); }

  // A C920-like webcam: auto exposure offers manual (1) and aperture priority (3) only.
  static FakeControlDevice uvc_webcam() {
    FakeControlDevice d;
    d.add_menu(V4L2_CID_POWER_LINE_FREQUENCY, "Power Line Frequency", {0, 1, 2}, 2);
    d.add_menu(V4L2_CID_EXPOSURE_AUTO, "Auto Exposure", {1, 3}, 3);
    d.add_bool(V4L2_CID_EXPOSURE_AUTO_PRIORITY, "Exposure, Dynamic Framerate", true);
    d.add_int(V4L2_CID_EXPOSURE_ABSOLUTE, "Exposure Time, Absolute", 3, 2047, 1, 250);
    d.add_int(V4L2_CID_GAIN, "Gain", 0, 255, 1, 64);
    d.add_bool(V4L2_CID_AUTO_WHITE_BALANCE, "White Balance, Automatic", true);
    d.add_int(V4L2_CID_WHITE_BALANCE_TEMPERATURE, "White Balance Temperature", 2000, 6500, 1, 4000);
    d.add_bool(V4L2_CID_FOCUS_AUTO, "Focus, Automatic Continuous", true);
    d.add_int(V4L2_CID_FOCUS_ABSOLUTE, "Focus, Absolute", 0, 250, 5, 30);
    return d;
  }

  std::optional<frames::ControlInfo> query(uint32_t id) override {
    auto it = controls_.find(id);
    if (it == controls_.end()) return std::nullopt;
    return it->second.info;
  }
  std::vector<frames::ControlInfo> list() override {
    std::vector<frames::ControlInfo> out;
    for (uint32_t id : order_) out.push_back(controls_.at(id).info);
    return out;
  }
  int get(uint32_t id, int32_t& value) override {
    auto it = controls_.find(id);
    if (it == controls_.end()) return EINVAL;
    value = it->second.value;
    return 0;
  }
  int set(uint32_t id, int32_t value) override {
    writes.push_back({id, value});
    auto it = controls_.find(id);
    if (it == controls_.end()) return EINVAL;
    frames::ControlInfo& info = it->second.info;
    if (info.read_only() || info.inactive()) return EACCES;
    if (!info.menu.empty()) {
      if (!info.offers(value)) return EINVAL;
    } else {
      int64_t v = std::clamp<int64_t>(value, info.minimum, info.maximum);
      v = info.minimum + (v - info.minimum + info.step / 2) / info.step * info.step;
      value = static_cast<int32_t>(std::min(v, info.maximum));
    }
    if (std::find(ignored_.begin(), ignored_.end(), id) == ignored_.end()) it->second.value = value;
    update_inactive();
    return 0;
  }
  std::string describe() const override { return "fake camera"; }

  int32_t value(uint32_t id) const { return controls_.at(id).value; }
  std::vector<std::pair<uint32_t, int32_t>> writes;  // every set() in order

 private:
  void update_inactive() {
    auto link = [this](uint32_t automatic, uint32_t manual, auto is_auto) {
      auto a = controls_.find(automatic), m = controls_.find(manual);
      if (a == controls_.end() || m == controls_.end()) return;
      if (is_auto(a->second.value))
        m->second.info.flags |= V4L2_CTRL_FLAG_INACTIVE;
      else
        m->second.info.flags &= ~V4L2_CTRL_FLAG_INACTIVE;
    };
    link(V4L2_CID_EXPOSURE_AUTO, V4L2_CID_EXPOSURE_ABSOLUTE, [](int32_t v) { return v != V4L2_EXPOSURE_MANUAL; });
    link(V4L2_CID_AUTO_WHITE_BALANCE, V4L2_CID_WHITE_BALANCE_TEMPERATURE, [](int32_t v) { return v != 0; });
    link(V4L2_CID_FOCUS_AUTO, V4L2_CID_FOCUS_ABSOLUTE, [](int32_t v) { return v != 0; });
  }
  std::map<uint32_t, Control> controls_;
  std::vector<uint32_t> order_;
  std::vector<uint32_t> ignored_;
};

}  // namespace bricklayer::test
