#include "bricklayer/projection/beeper.h"

#include <algorithm>
#include <cmath>

#include "bricklayer/common/log.h"

namespace bricklayer::projection {

std::vector<int16_t> make_tone(const ToneOptions& options, int sample_rate) {
  const int n = std::max(1, static_cast<int>(static_cast<int64_t>(sample_rate) * options.duration_ms / 1000));
  const int fade = std::max(1, std::min(n / 2, sample_rate / 200));
  const double amplitude = std::clamp(options.volume, 0.0, 1.0) * 32767.0;
  std::vector<int16_t> out(n);
  for (int i = 0; i < n; ++i) {
    const double envelope = std::min({1.0, static_cast<double>(i) / fade, static_cast<double>(n - 1 - i) / fade});
    out[i] = static_cast<int16_t>(std::lround(amplitude * envelope *
                                              std::sin(2.0 * M_PI * options.frequency_hz * i / sample_rate)));
  }
  return out;
}

Beeper::Beeper(const ToneOptions& options) {
  if (SDL_InitSubSystem(SDL_INIT_AUDIO) != 0) {
    log::warn("no audio (", SDL_GetError(), "): the beep is off");
    return;
  }
  SDL_AudioSpec want{};
  want.freq = options.sample_rate;
  want.format = AUDIO_S16SYS;
  want.channels = 1;
  want.samples = 512;
  SDL_AudioSpec have{};
  device_ = SDL_OpenAudioDevice(nullptr, 0, &want, &have, 0);
  if (device_ == 0) {
    log::warn("cannot open an audio device (", SDL_GetError(), "): the beep is off");
    SDL_QuitSubSystem(SDL_INIT_AUDIO);
    return;
  }
  sample_rate_ = have.freq;
  tone_ = make_tone(options, sample_rate_);
  SDL_PauseAudioDevice(device_, 0);
  log::info("audio: ", SDL_GetCurrentAudioDriver(), " driver, ", sample_rate_, " Hz");
}

Beeper::~Beeper() {
  if (device_ != 0) {
    SDL_CloseAudioDevice(device_);
    SDL_QuitSubSystem(SDL_INIT_AUDIO);
  }
}

void Beeper::beep() {
  ++beeps_;
  if (device_ == 0) return;
  SDL_ClearQueuedAudio(device_);
  SDL_QueueAudio(device_, tone_.data(), static_cast<Uint32>(tone_.size() * sizeof(int16_t)));
}

}  // namespace bricklayer::projection
