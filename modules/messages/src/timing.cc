#include "bricklayer/messages/timing.h"

namespace bricklayer::messages {

timing_t make_timing(const std::string& module, const std::string& stage, int64_t utime, int64_t frame_number,
                     int64_t elapsed_us, int64_t received_utime) {
  timing_t t{};
  t.utime = utime;
  t.frame_number = frame_number;
  t.module = module;
  t.stage = stage;
  t.elapsed_us = elapsed_us;
  t.received_utime = received_utime;
  return t;
}

}  // namespace bricklayer::messages
