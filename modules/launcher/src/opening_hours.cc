#include "bricklayer/launcher/opening_hours.h"

#include <algorithm>
#include <cctype>
#include <cstdio>
#include <cstdlib>
#include <stdexcept>

namespace bricklayer::launcher {
namespace {

const char* const kDays[7] = {"Mon", "Tue", "Wed", "Thu", "Fri", "Sat", "Sun"};

std::string trim(const std::string& s) {
  size_t b = 0, e = s.size();
  while (b < e && std::isspace(static_cast<unsigned char>(s[b]))) ++b;
  while (e > b && std::isspace(static_cast<unsigned char>(s[e - 1]))) --e;
  return s.substr(b, e - b);
}

int parse_day(const std::string& text) {
  for (int d = 0; d < 7; ++d) {
    const std::string name = kDays[d];
    if (text.size() == 3 && std::equal(text.begin(), text.end(), name.begin(), [](char a, char b) {
          return std::tolower(static_cast<unsigned char>(a)) == std::tolower(static_cast<unsigned char>(b));
        }))
      return d;
  }
  throw std::invalid_argument("'" + text + "' is not a day (Mon, Tue, Wed, Thu, Fri, Sat, Sun)");
}

// "Tue-Sun" -> bits 1..6; "Sat-Mon" wraps over the week's end.
unsigned parse_days(const std::string& text) {
  const auto dash = text.find('-');
  if (dash == std::string::npos) return 1u << parse_day(text);
  const int first = parse_day(text.substr(0, dash));
  const int last = parse_day(text.substr(dash + 1));
  unsigned mask = 0;
  for (int d = first;; d = (d + 1) % 7) {
    mask |= 1u << d;
    if (d == last) break;
  }
  return mask;
}

}  // namespace

LocalTime local_time_of(std::time_t t) {
  std::tm tm{};
  localtime_r(&t, &tm);
  // tm_wday: 0 = Sunday; ours: 0 = Monday. A leap second (tm_sec 60) counts as the minute's last.
  return LocalTime{(tm.tm_wday + 6) % 7, std::min(kSecondsPerDay - 1, tm.tm_hour * 3600 + tm.tm_min * 60 + tm.tm_sec)};
}

LocalTime advance(LocalTime t, int64_t seconds) {
  int64_t w = (static_cast<int64_t>(t.weekday) * kSecondsPerDay + t.second + seconds) % kSecondsPerWeek;
  if (w < 0) w += kSecondsPerWeek;
  return LocalTime{static_cast<int>(w / kSecondsPerDay), static_cast<int>(w % kSecondsPerDay)};
}

int64_t seconds_from(LocalTime from, LocalTime to) {
  int64_t d = (static_cast<int64_t>(to.weekday) - from.weekday) * kSecondsPerDay + (to.second - from.second);
  d %= kSecondsPerWeek;
  return d < 0 ? d + kSecondsPerWeek : d;
}

int parse_clock(const std::string& text, bool allow_24) {
  const std::string range = allow_24 ? "00:00 to 24:00" : "00:00 to 23:59";
  auto digit = [&](size_t i) { return i < text.size() && std::isdigit(static_cast<unsigned char>(text[i])); };
  if (text.size() != 5 || !digit(0) || !digit(1) || text[2] != ':' || !digit(3) || !digit(4))
    throw std::invalid_argument("'" + text + "' is not a time (HH:MM, " + range + ")");
  const int h = (text[0] - '0') * 10 + (text[1] - '0');
  const int m = (text[3] - '0') * 10 + (text[4] - '0');
  if (m > 59 || h > 24 || (h == 24 && (m != 0 || !allow_24)))
    throw std::invalid_argument("'" + text + "' is not a time of day (" + range + ")");
  return h * 3600 + m * 60;
}

std::string clock_text(int second_of_day) {
  char buf[16];
  std::snprintf(buf, sizeof buf, "%02d:%02d", second_of_day / 3600, (second_of_day / 60) % 60);
  return buf;
}

std::string weekday_name(int weekday) { return kDays[((weekday % 7) + 7) % 7]; }

OpeningHours OpeningHours::parse(const std::string& text) {
  OpeningHours hours;
  hours.text_ = trim(text);
  if (hours.text_.empty())
    throw std::invalid_argument("empty (give \"09:30-18:00\", or leave the key out to stay open all the time)");
  size_t pos = 0;
  while (pos <= text.size()) {
    const auto comma = text.find(',', pos);
    const std::string part = trim(text.substr(pos, comma == std::string::npos ? std::string::npos : comma - pos));
    pos = comma == std::string::npos ? text.size() + 1 : comma + 1;
    if (part.empty()) throw std::invalid_argument("an empty period (two commas, or a comma at an end)");
    Period p;
    std::string times = part;
    const auto space = part.find_last_of(" \t");
    if (space != std::string::npos) {
      p.days = parse_days(trim(part.substr(0, space)));
      times = part.substr(space + 1);
    }
    const auto dash = times.find('-');
    if (dash == std::string::npos)
      throw std::invalid_argument("'" + part + "' is not a period ([DAYS ]HH:MM-HH:MM, e.g. 09:30-18:00 or Tue-Sun 10:00-18:00)");
    p.start = parse_clock(times.substr(0, dash));
    p.end = parse_clock(times.substr(dash + 1), true);
    if (p.end == p.start)
      throw std::invalid_argument("'" + part + "' opens and closes at the same time (all day: 00:00-24:00)");
    hours.periods_.push_back(p);
  }
  return hours;
}

bool OpeningHours::open_at(LocalTime t) const {
  if (periods_.empty()) return true;
  const int yesterday = (t.weekday + 6) % 7;
  for (const Period& p : periods_) {
    const bool today = p.days & (1u << t.weekday);
    if (p.start < p.end) {
      if (today && t.second >= p.start && t.second < p.end) return true;
    } else {  // crosses midnight: the evening of its day and the early hours of the next
      if (today && t.second >= p.start) return true;
      if ((p.days & (1u << yesterday)) && t.second < p.end) return true;
    }
  }
  return false;
}

int64_t OpeningHours::seconds_until_open(LocalTime t) const {
  if (open_at(t)) return 0;
  int64_t best = kSecondsPerWeek;
  for (const Period& p : periods_) {
    for (int d = 0; d < 7; ++d) {
      if (!(p.days & (1u << d))) continue;
      const int64_t ahead = seconds_from(t, LocalTime{d, p.start});
      if (ahead > 0) best = std::min(best, ahead);
    }
  }
  return best;
}

std::string OpeningHours::closed_until(LocalTime t) const {
  const int64_t ahead = seconds_until_open(t);
  if (ahead == 0) return "";
  const LocalTime at = advance(t, ahead);
  return "closed until " + (ahead < kSecondsPerDay ? "" : weekday_name(at.weekday) + " ") + clock_text(at.second);
}

bool passes(LocalTime prev, LocalTime now, int second_of_day) {
  const int64_t step = seconds_from(prev, now);
  if (step == 0 || step > 3 * 3600) return false;
  // The restart time's next occurrence after prev, on any day.
  int64_t ahead = (static_cast<int64_t>(second_of_day) - prev.second) % kSecondsPerDay;
  if (ahead <= 0) ahead += kSecondsPerDay;
  return ahead <= step;
}

TestClock parse_test_clock(const std::string& text) {
  TestClock clock;
  std::string rest = trim(text);
  const std::string what = "BRICKLAYER_LAUNCHER_CLOCK '" + text + "'";
  const auto x = rest.find(" x");
  if (x != std::string::npos) {
    char* end = nullptr;
    const std::string speed = rest.substr(x + 2);
    clock.speed = std::strtod(speed.c_str(), &end);
    if (speed.empty() || *end != '\0' || !(clock.speed > 0) || clock.speed > 10000)
      throw std::invalid_argument(what + ": the speed after ' x' must be a number in (0, 10000]");
    rest = trim(rest.substr(0, x));
  }
  std::string time = rest;
  clock.start.weekday = local_time_of(std::time(nullptr)).weekday;
  const auto space = rest.find(' ');
  try {
    if (space != std::string::npos) {
      clock.start.weekday = parse_day(rest.substr(0, space));
      time = trim(rest.substr(space + 1));
    }
    if (time.size() != 8 || time[5] != ':' || !std::isdigit(static_cast<unsigned char>(time[6])) ||
        !std::isdigit(static_cast<unsigned char>(time[7])))
      throw std::invalid_argument("'" + time + "' is not HH:MM:SS");
    const int s = (time[6] - '0') * 10 + (time[7] - '0');
    if (s > 59) throw std::invalid_argument("'" + time + "' is not HH:MM:SS");
    clock.start.second = parse_clock(time.substr(0, 5)) + s;
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(what + ": " + e.what() + " (expected \"[DAY ]HH:MM:SS[ xSPEED]\")");
  }
  return clock;
}

}  // namespace bricklayer::launcher
