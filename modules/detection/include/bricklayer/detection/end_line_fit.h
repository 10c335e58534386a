// Where an end line really is: its profile fitted as the blurred glass-to-face step it is.
//
// Why: the detector places a line at the centroid of its dip, which is right for a symmetric dip. An end
// line is not one: it lies at the block's end, with the bare glass on its outer side and the block's face
// (a little darker, 0.94 of the glass in simcam; under the game's red and blue light darker or brighter
// again, and with the projected light's own edge on the block's end) on its inner side. Blur mixes that
// step into the dip and pulls the centroid inwards, by more the blurrier the frame: block lengths read up
// to 0.25% short at the mild level and 0.5% at the harsh one, the board scale that much large, 0.01-0.025
// block lengths at x = 5. A bias that depends on the frame's blur and on the light cannot be taken off as a
// constant (a fixed step and the frame's line width over-correct sharp frames and under-correct under
// projected light). So the profile across the line is fitted with a model that has the step in it:
//     level(x) = p0 + p1 S(x - (c - w/2)) + p2 S(x - (c + w/2)) + p3 (x - c),
// S the Gaussian-blurred unit step of width sigma: the levels outside (p0), on the line (p0 + p1) and inside
// (p0 + p1 + p2) are whatever the frame shows, w is the line's physical width, and the centre c and the blur
// sigma are searched (the levels are linear given c and sigma: variable projection, Nelder-Mead over the
// two). The slope p3 takes a shadow's or a gradient's lean across the window. The projector's light is not
// subtracted sharp, as the detector does (that leaves a light-dark pair at the block's end wherever the
// game lights a block, which the fit would read as a step): its prediction is blurred by the same sigma and
// taken off the profile inside the fit. The fitted centre is the line's middle whatever the step, the blur
// or the light.
#pragma once

#include <optional>
#include <vector>

namespace bricklayer::detection {

struct EndLineFit {
  double centre = 0.0;  // the line's middle, pixels of the profile
  double sigma = 0.0;   // the blur fitted, pixels
  double depth = 0.0;   // how dark the line is below the mean of the levels either side (profile units)
  double rms = 0.0;     // RMS of the fit's residuals (profile units)
};

// Fits the end line near `guess` (pixels, e.g. the detector's centroid) in `profile` (levels at integer
// positions 0..n-1, as the camera saw them), using the samples within `half_window` pixels of the guess;
// `line_width` is the line's width in pixels. `leakage` (empty, or one level per profile sample) is the
// projector's light predicted in the same profile, sharp: it is blurred with the sigma being fitted and taken
// off, so the light's own edge (the game lights each block up to its ends) is not read as part of the step.
// Nothing when the window leaves the profile, the fit does not converge near the guess (more than 2 px off),
// or the line is not darker than both sides.
std::optional<EndLineFit> fit_end_line(const std::vector<float>& profile, const std::vector<float>& leakage, double guess,
                                       double line_width, double half_window);

}  // namespace bricklayer::detection
