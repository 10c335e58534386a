#include "bricklayer/doctor/audio_check.h"
#include "bricklayer/doctor/quiet_stderr.h"

#include <SDL.h>

#include <string>

namespace bricklayer::doctor {
CheckResult check_audio(const HostPlan& plan) {
  const std::string name = "audio";
  if (!plan.projection) return CheckResult::ok(name, "profile " + plan.profile + " runs no projection");
  if (!plan.audio) return CheckResult::ok(name, "projection runs with --mute");
  QuietStderr quiet;
  const std::string fix = "connect speakers and check them with 'speaker-test -c 2 -l 1'; unset SDL_AUDIODRIVER";
  if (SDL_InitSubSystem(SDL_INIT_AUDIO) != 0)
    return CheckResult::warning(name, std::string("no audio driver (") + SDL_GetError() + "): the exhibit would not beep", fix);
  const std::string driver = SDL_GetCurrentAudioDriver() ? SDL_GetCurrentAudioDriver() : "?";
  SDL_AudioSpec want{}, have{};
  want.freq = 48000;
  want.format = AUDIO_S16SYS;
  want.channels = 1;
  want.samples = 512;
  const SDL_AudioDeviceID dev = SDL_OpenAudioDevice(nullptr, 0, &want, &have, 0);
  std::string error = dev == 0 ? SDL_GetError() : "";
  const int devices = SDL_GetNumAudioDevices(0);
  const std::string first = devices > 0 && SDL_GetAudioDeviceName(0, 0) ? SDL_GetAudioDeviceName(0, 0) : "the default device";
  if (dev != 0) SDL_CloseAudioDevice(dev);
  SDL_QuitSubSystem(SDL_INIT_AUDIO);
  if (dev == 0)
    return CheckResult::warning(name, "the " + driver + " driver cannot open an output (" + error + "): the exhibit would not beep", fix);
  // SDL's dummy and disk drivers open, but no one hears them.
  if (driver == "dummy" || driver == "disk")
    return CheckResult::warning(name, "SDL's " + driver + " audio driver: the beep reaches no speaker", fix);
  return CheckResult::ok(name, driver + " driver, " + first + ", " + std::to_string(have.freq) + " Hz");
}

}  // namespace bricklayer::doctor
