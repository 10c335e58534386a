// Camera frames in and stacks out: decoding image_t defensively, and writing detections as stack_t or
// as bricklayer-predict's JSON input.
#pragma once

#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "bricklayer/calibration_t.hpp"
#include "bricklayer/image_t.hpp"
#include "bricklayer/stack_t.hpp"
#include "bricklayer/vision/detector.h"
#include "bricklayer/vision/temporal_filter.h"

namespace bricklayer::vision {

inline constexpr int kMaxFrameSide = 8192;

// Decodes a frame to BGR8 or GRAY8. Returns an empty Mat and sets *error for: unknown format, zero or
// oversized width/height, size not matching data or width*height(*3), undecodable or truncated
// JPEG/PNG, decoded size different from width x height.
cv::Mat decode_image(const image_t& image, std::string* error);

// Encodes a frame as image_t (PNG or JPEG, or raw GRAY8/BGR8) for publishers and tests.
image_t encode_image(const cv::Mat& frame, int32_t format, int64_t utime, int64_t frame_number,
                     const std::string& source, int jpeg_quality = 90);

// Block height in block lengths of a board frame.
double block_height_blocks(const BoardFrame& frame);

// A stack message from a detection (ids 0.. left to right, bottom row first) or from filtered blocks.
stack_t to_stack_message(const Detection& detection, const BoardFrame& frame, int64_t utime, int64_t frame_number);
stack_t to_stack_message(const std::vector<FilteredBlock>& blocks, const BoardFrame& frame, int64_t utime,
                         int64_t frame_number);
stack_t no_frame_stack(const BoardFrame& frame, int64_t utime, int64_t frame_number);

// One line of bricklayer-predict's input:
// {"block_length":1,"block_height":h,"table_edge":0,"blocks":[{"id":0,"row":0,"x":-0.5},...]}.
std::string to_predict_json(const Detection& detection, const BoardFrame& frame);

}  // namespace bricklayer::vision
