#include "bricklayer/inspect/wall_clock.h"

#include <cstdio>
#include <ctime>

namespace bricklayer::inspect {

std::string utc_text(int64_t utime_us) {
  int64_t seconds = utime_us / 1000000;
  int64_t micros = utime_us % 1000000;
  if (micros < 0) {  // floor, so times before 1970 print as the calendar does
    micros += 1000000;
    seconds -= 1;
  }
  std::time_t t = static_cast<std::time_t>(seconds);
  std::tm tm{};
  if (!gmtime_r(&t, &tm)) return "";
  char buf[64];
  std::snprintf(buf, sizeof buf, "%04d-%02d-%02d %02d:%02d:%02d.%06lld", tm.tm_year + 1900, tm.tm_mon + 1, tm.tm_mday,
                tm.tm_hour, tm.tm_min, tm.tm_sec, static_cast<long long>(micros));
  return buf;
}

bool is_utime_name(const std::string& member) {
  return member == "utime" || (member.size() > 6 && member.compare(member.size() - 6, 6, "_utime") == 0);
}

}  // namespace bricklayer::inspect
