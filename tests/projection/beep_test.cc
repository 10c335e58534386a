// The beep through SDL's disk audio driver: the samples land in SDL_DISKAUDIOFILE.
#include "bricklayer/projection/beeper.h"

#include <catch2/catch.hpp>

#include <chrono>
#include <cstring>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <thread>
#include <unistd.h>

#include "bricklayer/projection/red_debounce.h"

using namespace bricklayer::projection;

TEST_CASE("a red block beeps once after its hold and not again while it stays red") {
  const std::filesystem::path file =
      std::filesystem::temp_directory_path() / ("bricklayer-beep-" + std::to_string(getpid()) + ".raw");
  setenv("SDL_AUDIODRIVER", "disk", 1);
  setenv("SDL_DISKAUDIOFILE", file.c_str(), 1);
  int sample_rate = 0;
  size_t tone_samples = 0;
  {
    Beeper beeper;
    REQUIRE(beeper.ok());
    sample_rate = beeper.sample_rate();
    tone_samples = beeper.tone().size();
    RedDebounce debounce(300, 1000);
    const auto start = std::chrono::steady_clock::now();
    for (;;) {
      const int64_t t = std::chrono::duration_cast<std::chrono::milliseconds>(std::chrono::steady_clock::now() - start).count();
      if (t > 1800) break;
      const bool red = t >= 200;  // red from 0.2 s on, and it stays
      if (debounce.update(red, t)) beeper.beep();
      std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
    CHECK(beeper.beeps() == 1);
  }
  std::ifstream in(file, std::ios::binary);
  std::vector<int16_t> samples((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  std::vector<int16_t> pcm(samples.size() / 2);
  std::memcpy(pcm.data(), samples.data(), pcm.size() * 2);
  std::filesystem::remove(file);
  // The first sounding sample comes after the hold: ~0.5 s into the file, never before 0.4 s.
  size_t first = 0, count = 0, bursts = 0, last = 0;
  for (size_t i = 0; i < pcm.size(); ++i) {
    if (pcm[i] == 0) continue;
    if (count == 0) first = i;
    if (count == 0 || i - last > static_cast<size_t>(sample_rate / 10)) ++bursts;
    last = i;
    ++count;
  }
  REQUIRE(count > 0);
  CHECK(bursts == 1);
  // The disk device may store the mono tone as stereo (two units per sample frame): accept 1 or 2
  // units per tone sample. Before the hold (0.2 s + 0.3 s) nothing sounds: the first unit lies past
  // 0.4 s of mono samples (0.2 s of stereo frames, still after red appeared and well before the beep
  // could have come without the hold in mono).
  INFO("rate " << sample_rate << ", tone " << tone_samples << " samples, file " << pcm.size() << " units");
  CHECK(first > static_cast<size_t>(0.4 * sample_rate));
  CHECK(count >= tone_samples * 9 / 10);
  CHECK(count <= 2 * tone_samples);
}
