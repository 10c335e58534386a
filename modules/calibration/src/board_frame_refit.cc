#include "bricklayer/calibration/board_frame_refit.h"

#include <algorithm>
#include <cstdio>
#include <opencv2/imgproc.hpp>

namespace bricklayer::calibration {

FrameCorrection FrameCorrection::after(const FrameCorrection& f) const {
  // [a2 b2 0; 0 a2 0; g2 h2 1] * [a1 b1 0; 0 a1 0; g1 h1 1].
  FrameCorrection out;
  out.scale = scale * f.scale;
  out.shear = scale * f.shear + shear * f.scale;
  out.keystone = keystone * f.scale + f.keystone;
  out.vertical_keystone = keystone * f.shear + vertical_keystone * f.scale + f.vertical_keystone;
  return out;
}

calibration_t FrameCorrection::apply(const calibration_t& calibration) const {
  return apply_frame_correction(calibration, scale, keystone, shear, vertical_keystone);
}

std::optional<FrameRefit> refit_board_frame(const calibration_t& corrected, const std::vector<RefitFrame>& frames, int max_row,
                                            int min_blocks, double max_residual, std::string* why) {
  detection::BlockScaleMeter meter(corrected, detection::DetectorConfig{}, max_row);
  std::vector<LineLean> leans;
  const double h = corrected.block_height;
  for (const RefitFrame& f : frames) {
    if (!f.projector_image.empty()) meter.set_projector_image(f.projector_image, f.projector_size);
    const size_t before = meter.measured().size();
    meter.add(f.bgr);
    // The leans in the green channel, where the game's red and blue light leaks least, inside each block's
    // band clear of its top and bottom edges.
    cv::Mat green;
    if (f.bgr.channels() == 3)
      cv::extractChannel(f.bgr, green, 1);
    else
      green = f.bgr;
    for (size_t i = before; i < meter.measured().size(); ++i) {
      const detection::EndLines& e = meter.measured()[i];
      const double y0 = (e.row + 0.2) * h, y1 = (e.row + 0.75) * h;
      for (double x : {e.left, e.right})
        if (const auto lean = measure_line_lean(green, corrected, x, y0, y1)) leans.push_back({x, *lean, 0.5 * (y0 + y1)});
    }
  }
  std::vector<detection::EndLines> measured = meter.measured();
  double lo = 1e300, hi = -1e300;
  for (const detection::EndLines& e : measured) lo = std::min(lo, e.y), hi = std::max(hi, e.y);
  FrameRefit out;
  out.height_span = measured.empty() ? 0.0 : hi - lo;
  if (out.height_span < detection::kMinHeightForVerticalKeystone) {
    // Blocks on the bottom row (and a block or two just above) say nothing the first pass did not; measured
    // again they only trade one frame's scatter for another's (the bench: the bottom row's error alike).
    char text[200];
    std::snprintf(text, sizeof text,
                  "the blocks measured span %.2f block lengths of height, need %.1f (a tower of blocks on a bottom-row block, "
                  "up to row 3 or higher)",
                  out.height_span, detection::kMinHeightForVerticalKeystone);
    if (why) *why = text;
    return std::nullopt;
  }
  for (const detection::EndLines& e : measured) out.highest_row = std::max(out.highest_row, e.row);
  const auto lengths = detection::fit_board_correction(measured, detection::DetectorConfig{}.line_width, min_blocks, max_residual, why);
  if (!lengths) return std::nullopt;
  out.lengths = *lengths;
  out.correction.scale = lengths->scale;
  out.correction.keystone = lengths->keystone;
  out.correction.vertical_keystone = lengths->vertical_keystone;
  out.lean = fit_shear(leans, lengths->scale, lengths->keystone, lengths->vertical_keystone, min_blocks, &out.lean_why);
  if (out.lean) out.correction.shear = out.lean->shear;
  return out;
}

}  // namespace bricklayer::calibration
