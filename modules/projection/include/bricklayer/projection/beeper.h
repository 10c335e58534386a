// A short tone through SDL audio (queued, so beep() never blocks). With SDL_AUDIODRIVER=disk the
// samples land in SDL_DISKAUDIOFILE, which is how the tests hear it.
#pragma once

#include <SDL.h>

#include <cstdint>
#include <vector>

namespace bricklayer::projection {

struct ToneOptions {
  int sample_rate = 44100;  // Hz
  int frequency_hz = 880;
  int duration_ms = 150;
  double volume = 0.5;      // 0..1 of full scale
};

class Beeper {
 public:
  // Opens the default audio device (signed 16-bit mono). When no device can be opened the beeper is
  // silent (ok() false, one warning) and the display carries on.
  explicit Beeper(const ToneOptions& options = {});
  ~Beeper();
  Beeper(const Beeper&) = delete;
  Beeper& operator=(const Beeper&) = delete;

  bool ok() const { return device_ != 0; }
  void beep();
  int64_t beeps() const { return beeps_; }
  const std::vector<int16_t>& tone() const { return tone_; }
  int sample_rate() const { return sample_rate_; }

 private:
  SDL_AudioDeviceID device_ = 0;
  std::vector<int16_t> tone_;
  int sample_rate_ = 0;
  int64_t beeps_ = 0;
};

// The tone's samples: a sine with 5 ms fades at both ends (no clicks).
std::vector<int16_t> make_tone(const ToneOptions& options, int sample_rate);

}  // namespace bricklayer::projection
