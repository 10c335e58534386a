#include "bricklayer/inspect/progress.h"

#include <unistd.h>

#include <cstdio>

namespace bricklayer::inspect {

Progress::Progress(std::string program, uint64_t total_bytes, bool enabled, double interval_s)
    : program_(std::move(program)), total_(total_bytes), enabled_(enabled), tty_(::isatty(2) == 1),
      interval_(interval_s), start_(Clock::now()), last_(start_) {}

void Progress::update(uint64_t done) {
  if (!enabled_) return;
  auto now = Clock::now();
  if (now - last_ < interval_) return;
  last_ = now;
  double elapsed = std::chrono::duration<double>(now - start_).count();
  double rate = elapsed > 0 ? static_cast<double>(done) / elapsed : 0;
  double left = rate > 0 && total_ > done ? static_cast<double>(total_ - done) / rate : 0;
  std::fprintf(stderr, "%s%s: %.1f of %.1f MB (%.0f%%), %.1f MB/s, about %.0f s left%s", tty_ ? "\r" : "",
               program_.c_str(), static_cast<double>(done) / 1e6, static_cast<double>(total_) / 1e6,
               total_ ? 100.0 * static_cast<double>(done) / static_cast<double>(total_) : 100.0, rate / 1e6, left,
               tty_ ? "   " : "\n");
  std::fflush(stderr);
  printed_ = true;
}

void Progress::finish() {
  if (printed_ && tty_) std::fprintf(stderr, "\n");
  printed_ = false;
}

}  // namespace bricklayer::inspect
