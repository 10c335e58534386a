#include "bricklayer/frames/v4l2_device.h"

#include <fcntl.h>
#include <linux/videodev2.h>
#include <sys/ioctl.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cstring>
#include <stdexcept>

namespace bricklayer::frames {
namespace {

// ioctl restarted when a signal interrupts it (the process's SIGTERM handler must not turn into a
// failed control).
int xioctl(int fd, unsigned long request, void* arg) {
  int r;
  do {
    r = ioctl(fd, request, arg);
  } while (r == -1 && errno == EINTR);
  return r == -1 ? errno : 0;
}

ControlInfo to_info(int fd, const v4l2_queryctrl& q) {
  ControlInfo info;
  info.id = q.id;
  info.name = std::string(reinterpret_cast<const char*>(q.name), strnlen(reinterpret_cast<const char*>(q.name), sizeof(q.name)));
  info.type = q.type;
  info.minimum = q.minimum;
  info.maximum = q.maximum;
  info.step = q.step;
  info.default_value = q.default_value;
  info.flags = q.flags;
  if (q.type == V4L2_CTRL_TYPE_MENU || q.type == V4L2_CTRL_TYPE_INTEGER_MENU) {
    // A menu may have holes (UVC's auto exposure often offers only 1 = manual and 3 = aperture priority).
    for (int64_t index = q.minimum; index <= q.maximum && index - q.minimum < 64; ++index) {
      v4l2_querymenu m{};
      m.id = q.id;
      m.index = static_cast<uint32_t>(index);
      if (xioctl(fd, VIDIOC_QUERYMENU, &m) == 0) info.menu.push_back(index);
    }
  }
  return info;
}

}  // namespace

bool ControlInfo::read_only() const { return (flags & (V4L2_CTRL_FLAG_READ_ONLY | V4L2_CTRL_FLAG_GRABBED)) != 0; }
bool ControlInfo::inactive() const { return (flags & V4L2_CTRL_FLAG_INACTIVE) != 0; }
bool ControlInfo::offers(int64_t menu_index) const {
  return std::find(menu.begin(), menu.end(), menu_index) != menu.end();
}

std::string v4l2_device_path(const std::string& device) {
  const bool numeric = !device.empty() && std::all_of(device.begin(), device.end(), [](unsigned char c) { return std::isdigit(c); });
  return numeric ? "/dev/video" + device : device;
}

V4l2ControlDevice::V4l2ControlDevice(const std::string& device) : path_(v4l2_device_path(device)) {
  fd_ = open(path_.c_str(), O_RDWR | O_NONBLOCK | O_CLOEXEC);
  if (fd_ < 0)
    throw std::runtime_error("cannot open " + path_ + ": " + std::strerror(errno) + " (is the camera connected? ls /dev/video*)");
  v4l2_capability cap{};
  if (int e = xioctl(fd_, VIDIOC_QUERYCAP, &cap); e != 0) {
    close(fd_);
    fd_ = -1;
    throw std::runtime_error(path_ + " is not a V4L2 device: " + std::strerror(e));
  }
  card_ = std::string(reinterpret_cast<const char*>(cap.card), strnlen(reinterpret_cast<const char*>(cap.card), sizeof(cap.card)));
}

V4l2ControlDevice::~V4l2ControlDevice() {
  if (fd_ >= 0) close(fd_);
}

std::optional<ControlInfo> V4l2ControlDevice::query(uint32_t id) {
  v4l2_queryctrl q{};
  q.id = id;
  if (xioctl(fd_, VIDIOC_QUERYCTRL, &q) != 0 || (q.flags & V4L2_CTRL_FLAG_DISABLED)) return std::nullopt;
  return to_info(fd_, q);
}

std::vector<ControlInfo> V4l2ControlDevice::list() {
  std::vector<ControlInfo> out;
  v4l2_queryctrl q{};
  q.id = V4L2_CTRL_FLAG_NEXT_CTRL;
  while (xioctl(fd_, VIDIOC_QUERYCTRL, &q) == 0 && out.size() < 1024) {
    if (!(q.flags & V4L2_CTRL_FLAG_DISABLED) && q.type != V4L2_CTRL_TYPE_CTRL_CLASS) out.push_back(to_info(fd_, q));
    q.id |= V4L2_CTRL_FLAG_NEXT_CTRL;
  }
  return out;
}

int V4l2ControlDevice::get(uint32_t id, int32_t& value) {
  v4l2_control c{};
  c.id = id;
  int e = xioctl(fd_, VIDIOC_G_CTRL, &c);
  if (e == 0) value = c.value;
  return e;
}

int V4l2ControlDevice::set(uint32_t id, int32_t value) {
  v4l2_control c{};
  c.id = id;
  c.value = value;
  return xioctl(fd_, VIDIOC_S_CTRL, &c);
}

}  // namespace bricklayer::frames
