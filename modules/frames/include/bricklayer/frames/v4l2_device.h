// The controls of a V4L2 camera, through the kernel's own ioctls (linux/videodev2.h: VIDIOC_QUERYCTRL,
// VIDIOC_QUERYMENU, VIDIOC_G_CTRL, VIDIOC_S_CTRL) rather than OpenCV's CAP_PROP values, which map only
// some controls and report nothing when the driver lacks one.
//
// ControlDevice is the seam: V4l2ControlDevice talks to the kernel; a test without a camera gives
// camera_controls.h a device of its own that behaves like a driver (clamps, inactive controls).
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace bricklayer::frames {

struct ControlInfo {
  uint32_t id = 0;
  std::string name;           // the driver's name ("Exposure, Auto")
  uint32_t type = 0;          // V4L2_CTRL_TYPE_*
  int64_t minimum = 0, maximum = 0, step = 1, default_value = 0;
  uint32_t flags = 0;         // V4L2_CTRL_FLAG_*
  std::vector<int64_t> menu;  // for menu controls: the indices the driver offers (VIDIOC_QUERYMENU)

  bool read_only() const;
  bool inactive() const;  // e.g. manual exposure while automatic exposure runs
  bool offers(int64_t menu_index) const;
};

class ControlDevice {
 public:
  virtual ~ControlDevice() = default;
  // nullopt when the driver has no such control (or it is disabled).
  virtual std::optional<ControlInfo> query(uint32_t id) = 0;
  // Every control the driver offers, in its order.
  virtual std::vector<ControlInfo> list() = 0;
  // 0 on success, else the errno of the ioctl.
  virtual int get(uint32_t id, int32_t& value) = 0;
  virtual int set(uint32_t id, int32_t value) = 0;
  virtual std::string describe() const = 0;
};

// "0" -> "/dev/video0"; a path stays as it is.
std::string v4l2_device_path(const std::string& device);

// A V4L2 device node opened for its controls only (a second open beside the capture is allowed by
// V4L2 and does not disturb streaming). Throws std::runtime_error when the node cannot be opened or
// is not a V4L2 device.
class V4l2ControlDevice final : public ControlDevice {
 public:
  explicit V4l2ControlDevice(const std::string& device);
  ~V4l2ControlDevice() override;
  V4l2ControlDevice(const V4l2ControlDevice&) = delete;
  V4l2ControlDevice& operator=(const V4l2ControlDevice&) = delete;

  std::optional<ControlInfo> query(uint32_t id) override;
  std::vector<ControlInfo> list() override;
  int get(uint32_t id, int32_t& value) override;
  int set(uint32_t id, int32_t value) override;
  std::string describe() const override { return path_ + " (" + card_ + ")"; }
  const std::string& card() const { return card_; }

 private:
  std::string path_;
  std::string card_;  // VIDIOC_QUERYCAP's card name ("HD Pro Webcam C920")
  int fd_ = -1;
};

}  // namespace bricklayer::frames
