// Camera frames on the bus: image_t <-> cv::Mat. One decoder that every module reading frames uses
// (vision, calibration, simcam's projector input), hardened against what a network can deliver, and
// one encoder that every publisher uses (camera, simcam, the soak, the end-to-end bench), so no module
// packs an image_t by hand.
#pragma once

#include <cstdint>
#include <string>

#include <opencv2/core.hpp>

#include "bricklayer/image_t.hpp"

namespace bricklayer::frames {

inline constexpr int kMaxFrameSide = 8192;

// Decodes a frame to BGR8 or GRAY8. Returns an empty Mat and sets *error for: unknown format, zero or
// oversized width/height, size not matching data or width*height(*3), undecodable or truncated
// JPEG/PNG, a JPEG/PNG header that declares another size than the message (checked before decoding,
// so a small file declaring a huge image allocates nothing), decoded size different from width x height.
// A replay's DecodeAhead (decode_ahead.h) may have decoded it already on another thread: the same
// bytes through decode_image_here, so the same result.
cv::Mat decode_image(const image_t& image, std::string* error);
// The same, always on the caller's thread.
cv::Mat decode_image_here(const image_t& image, std::string* error);

// Encodes a BGR8 or GRAY8 frame as image_t: FORMAT_JPEG (at jpeg_quality), FORMAT_PNG (OpenCV's
// default settings) or raw FORMAT_GRAY8 / FORMAT_BGR8. Throws std::invalid_argument for an empty,
// oversized or wrongly typed frame or an unknown format, std::runtime_error when OpenCV fails.
image_t encode_image(const cv::Mat& frame, int32_t format, int64_t utime, int64_t frame_number,
                     const std::string& source, int jpeg_quality = 90);

// "jpeg" -> FORMAT_JPEG, "png" -> FORMAT_PNG (the --format flag of the publishers); throws
// std::invalid_argument for anything else.
int32_t image_format(const std::string& name);

}  // namespace bricklayer::frames
