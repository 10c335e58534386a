// The calibration file loader: bricklayer::board::parse_calibration_json (the strict loader that
// bricklayer-calibrate, vision and projection use). Any bytes give a calibration or a clear
// CalibrationFileError; a calibration the strict loader accepts must survive a save/parse round trip,
// and the vision detector (which builds its remap tables from it) must take it or refuse it with
// std::invalid_argument, never crash.
#include <cstdint>
#include <stdexcept>
#include <string>

#include "bricklayer/board/calibration_file.h"
#include "bricklayer/detection/detector.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size > (1 << 20) + 16) return 0;
  const std::string text(reinterpret_cast<const char*>(data), size);
  try {
    const bricklayer::calibration_t cal = bricklayer::board::parse_calibration_json(text);
    const std::string again = bricklayer::board::calibration_to_json(cal);
    (void)bricklayer::board::parse_calibration_json(again);
    // Only small images: the detector's remap tables are sized by the calibration's camera image.
    if (static_cast<int64_t>(cal.camera_width) * cal.camera_height <= 1280 * 960) {
      bricklayer::detection::Detector detector;
      try {
        detector.set_calibration(cal);
      } catch (const std::invalid_argument&) {
      }
    }
  } catch (const bricklayer::board::CalibrationFileError&) {
  }
  return 0;
}
