// Vision's frame entry: image_t bytes -> decode_image() -> Detector::detect(), as bricklayer-vision runs
// them on every BL_IMAGE message. Any bytes give a frame or a decode error, never a crash, an
// out-of-bounds read or an allocation beyond what the header may claim.
//
// Input layout: byte 0 picks the mode.
//   mode even: the rest is an LCM-encoded image_t (exactly what arrives on the bus).
//   mode odd:  bytes 1..4 width, 5..8 height (little-endian int32), 9 format; the rest is the data.
//              (lets the fuzzer reach the image codecs without first learning LCM's framing)
// A decoded frame is scaled to the detector's camera size (640x480) so the detector sees the fuzzed
// pixels; bit 1 of the mode also installs it as the projector image (leakage subtraction path).
#include <cstdint>
#include <cstring>
#include <string>

#include <opencv2/imgproc.hpp>

#include "bricklayer/image_t.hpp"
#include "bricklayer/detection/detector.h"
#include "bricklayer/frames/image_codec.h"

namespace {
int32_t read_i32(const uint8_t* p) {
  uint32_t v = 0;
  std::memcpy(&v, p, 4);
  return static_cast<int32_t>(v);
}
}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size < 1 || size > (4 << 20)) return 0;
  static bricklayer::detection::Detector detector;  // default geometry: a 640x480 camera
  const uint8_t mode = data[0];
  bricklayer::image_t image{};
  if (mode % 2 == 0) {
    if (image.decode(data + 1, 0, static_cast<int>(size - 1)) < 0) return 0;
  } else {
    if (size < 10) return 0;
    image.width = read_i32(data + 1);
    image.height = read_i32(data + 5);
    image.format = data[9] % 6;
    image.data.assign(data + 10, data + size);
    image.size = static_cast<int32_t>(image.data.size());
  }
  std::string error;
  cv::Mat frame = bricklayer::frames::decode_image(image, &error);
  if (frame.empty()) {
    if (error.empty()) __builtin_trap();  // every rejection must say why
    return 0;
  }
  // Uncalibrated, the detector takes any frame size; scale to the default camera's 640x480.
  const cv::Size camera = detector.frame().camera_size().empty() ? cv::Size(640, 480) : detector.frame().camera_size();
  if (frame.size() != camera) {
    cv::Mat scaled;
    cv::resize(frame, scaled, camera, 0, 0, cv::INTER_NEAREST);
    frame = scaled;
  }
  if (mode & 2) {
    cv::Mat bgr = frame;
    if (bgr.channels() == 1) cv::cvtColor(frame, bgr, cv::COLOR_GRAY2BGR);
    detector.set_projector_image(bgr, cv::Size(1280, 720));
  } else {
    detector.clear_projector_image();
  }
  const bricklayer::detection::Detection d = detector.detect(frame);
  for (const auto& b : d.blocks) {
    if (b.confidence < 0 || b.confidence > 1 || b.x != b.x) __builtin_trap();
  }
  return 0;
}
