// Fuzz target: LogReader on arbitrary bytes (a torn, truncated or hostile log). Every byte of the file
// must be accounted for, either inside an intact event or inside a reported damaged region.
#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <string>

#include "bricklayer/runtime/log_file.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size > (1 << 20)) return 0;
  static const std::string path = "/tmp/bricklayer-fuzz-log-" + std::to_string(::getpid());
  {
    std::FILE* f = std::fopen(path.c_str(), "wb");
    if (!f) return 0;
    std::fwrite(data, 1, size, f);
    std::fclose(f);
  }
  bricklayer::runtime::LogReader reader(path);
  bricklayer::runtime::LogEvent e;
  int64_t covered = 0;
  while (reader.next(e))
    covered += bricklayer::runtime::kLogEventHeaderBytes + static_cast<int64_t>(e.channel.size() + e.data.size());
  for (const auto& d : reader.damage()) covered += d.bytes;
  if (covered != static_cast<int64_t>(size)) __builtin_trap();
  return 0;
}
