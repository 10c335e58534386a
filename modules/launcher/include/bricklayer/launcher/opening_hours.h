// The exhibit's opening hours and its nightly restart, as a profile gives them
// ("opening_hours": "09:30-18:00" or "Tue-Sun 10:00-18:00, Mon 12:00-18:00"; "nightly_restart": "03:00"),
// and the local wall clock they are read against. These are the one place where the launcher uses wall
// time: a museum opens at 09:30 on the clock on the wall. Pure: every question takes the local time it
// is about, so tests ask with given times and the launcher asks with its clock (the machine's local
// time, or the test clock of BRICKLAYER_LAUNCHER_CLOCK, see parse_test_clock).
//
// Times are plain "HH:MM" of local time: no time zone and no DST rule is parsed. When the clocks change,
// the schedule follows the wall clock: an hour that is skipped passes in one step (a restart time inside
// it still fires, once), an hour that is repeated is lived twice (a restart time inside it fires twice
// that night; 03:00 is outside the repeated hour in Europe).
#pragma once

#include <ctime>
#include <cstdint>
#include <string>
#include <vector>

namespace bricklayer::launcher {

inline constexpr int kSecondsPerDay = 86400;
inline constexpr int64_t kSecondsPerWeek = 7LL * kSecondsPerDay;

// A moment of the local week: weekday 0 = Monday ... 6 = Sunday, seconds since local midnight.
struct LocalTime {
  int weekday = 0;
  int second = 0;  // [0, 86400)
};

LocalTime local_time_of(std::time_t t);  // the machine's local time (localtime_r)
LocalTime advance(LocalTime t, int64_t seconds);
// Seconds forward from `from` to `to` on the weekly clock, in [0, one week).
int64_t seconds_from(LocalTime from, LocalTime to);

// "HH:MM" (two digits each, 00:00 to 23:59; "24:00" too when allow_24 is set, the end of a day) to
// seconds since midnight. Throws std::invalid_argument saying what is wrong.
int parse_clock(const std::string& text, bool allow_24 = false);
std::string clock_text(int second_of_day);  // "09:30"
std::string weekday_name(int weekday);      // "Mon"

class OpeningHours {
 public:
  // Always open: a profile without opening_hours.
  OpeningHours() = default;
  // One or more periods separated by commas, each "[DAYS ]HH:MM-HH:MM"; DAYS is a day ("Mon") or a range
  // ("Tue-Sun", "Sat-Mon"), every day without it. A period that ends before it starts crosses midnight
  // ("18:00-02:00" belongs to the day it starts on). Throws std::invalid_argument naming what is wrong.
  static OpeningHours parse(const std::string& text);

  bool always_open() const { return periods_.empty(); }
  bool open_at(LocalTime t) const;
  // Seconds until the next opening; 0 when open at t.
  int64_t seconds_until_open(LocalTime t) const;
  // "closed until 09:30" (the next opening within a day), "closed until Tue 09:30"; "" when open at t.
  std::string closed_until(LocalTime t) const;
  const std::string& text() const { return text_; }

 private:
  struct Period {
    unsigned days = 0x7f;  // bit d: the period starts on weekday d
    int start = 0;         // seconds since midnight
    int end = 0;           // <= start: crosses midnight, ends the next day
  };
  std::vector<Period> periods_;
  std::string text_;
};

// Whether the local clock passes `second_of_day` between two readings (the launcher reads it every
// tick): the time lies in (prev, now]. Fires once per passage whatever the tick: the next reading's
// interval starts where this one ended. A step of more than three hours between readings is the clock
// being set (NTP at boot, by hand), not time passing: it fires nothing.
bool passes(LocalTime prev, LocalTime now, int second_of_day);

// The test clock (BRICKLAYER_LAUNCHER_CLOCK, read only by bricklayer-launch, for tests): "[DAY ]HH:MM:SS[ xSPEED]",
// the local time the launcher's schedule starts at and how many times faster than real time it runs
// ("Wed 09:59:30 x30": half a minute before ten on a Wednesday, a minute every two seconds).
struct TestClock {
  LocalTime start;
  double speed = 1;
};
TestClock parse_test_clock(const std::string& text);  // throws std::invalid_argument

}  // namespace bricklayer::launcher
