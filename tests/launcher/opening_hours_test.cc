// The opening hours and the nightly restart as pure questions about given local times: crossing
// midnight, days, the next opening in words, the restart firing once per passage of its time whatever
// the tick, a restart time inside the closed hours, the test clock, and bad values (with the profile's
// line) at load.
#include <catch2/catch.hpp>

#include <stdexcept>

#include "bricklayer/launcher/opening_hours.h"
#include "bricklayer/launcher/profile.h"
#include "profile_error.h"

using namespace bricklayer::launcher;
using bricklayer::test::profile_error;

namespace {
constexpr int kMon = 0, kTue = 1, kWed = 2, kSat = 5, kSun = 6;
LocalTime at(int weekday, const std::string& hhmm, int s = 0) { return LocalTime{weekday, parse_clock(hhmm) + s}; }

std::string error_of(const std::string& text) {
  try {
    OpeningHours::parse(text);
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "";
}
}  // namespace

TEST_CASE("opening hours within one day: open from the opening minute up to, not including, the closing one") {
  const OpeningHours h = OpeningHours::parse("09:30-18:00");
  CHECK_FALSE(h.always_open());
  CHECK_FALSE(h.open_at(at(kWed, "09:29", 59)));
  CHECK(h.open_at(at(kWed, "09:30")));
  CHECK(h.open_at(at(kWed, "17:59", 59)));
  CHECK_FALSE(h.open_at(at(kWed, "18:00")));
  CHECK_FALSE(h.open_at(at(kWed, "03:00")));
  CHECK(h.seconds_until_open(at(kWed, "12:00")) == 0);
  CHECK(h.closed_until(at(kWed, "12:00")).empty());
  // After closing: tomorrow's opening, said as a time (within a day).
  CHECK(h.seconds_until_open(at(kWed, "18:00")) == 15 * 3600 + 30 * 60);
  CHECK(h.closed_until(at(kWed, "18:00")) == "closed until 09:30");
  CHECK(h.closed_until(at(kWed, "00:10")) == "closed until 09:30");
  CHECK(h.seconds_until_open(at(kWed, "09:29", 30)) == 30);
}

TEST_CASE("a period that crosses midnight belongs to the day it starts on") {
  const OpeningHours h = OpeningHours::parse("Fri-Sat 20:00-02:00");
  CHECK(h.open_at(at(4, "20:00")));             // Friday evening
  CHECK(h.open_at(at(kSat, "01:59", 59)));       // Friday's night, after midnight
  CHECK_FALSE(h.open_at(at(kSat, "02:00")));
  CHECK(h.open_at(at(kSat, "23:00")));
  CHECK(h.open_at(at(kSun, "00:30")));           // Saturday's night
  CHECK_FALSE(h.open_at(at(kSun, "20:00")));     // no Sunday evening
  CHECK_FALSE(h.open_at(at(4, "01:00")));        // Thursday had no evening
  CHECK(h.closed_until(at(kSun, "02:00")) == "closed until Fri 20:00");
  CHECK(h.seconds_until_open(at(kSun, "02:00")) == 5 * 86400 + 18 * 3600);
  // Every day, over midnight.
  const OpeningHours night = OpeningHours::parse("22:00-06:00");
  CHECK(night.open_at(at(kMon, "23:59", 59)));
  CHECK(night.open_at(at(kTue, "00:00")));
  CHECK(night.open_at(at(kMon, "05:00")));  // Sunday's night: the week wraps
  CHECK_FALSE(night.open_at(at(kMon, "06:00")));
  CHECK(night.closed_until(at(kMon, "06:00")) == "closed until 22:00");
}

TEST_CASE("days, several periods and the whole day") {
  const OpeningHours h = OpeningHours::parse("Tue-Sun 10:00-18:00, Mon 12:00-14:00");
  CHECK_FALSE(h.open_at(at(kMon, "11:00")));
  CHECK(h.open_at(at(kMon, "13:00")));
  CHECK_FALSE(h.open_at(at(kMon, "15:00")));
  CHECK(h.open_at(at(kTue, "10:00")));
  CHECK(h.open_at(at(kSun, "17:00")));
  CHECK(h.closed_until(at(kSun, "18:00")) == "closed until 12:00");  // Monday noon, within a day
  CHECK(h.closed_until(at(kMon, "08:00")) == "closed until 12:00");
  const OpeningHours weekend = OpeningHours::parse("sat-mon 10:00-12:00");  // wraps over the week's end, any case
  CHECK(weekend.open_at(at(kSat, "11:00")));
  CHECK(weekend.open_at(at(kSun, "11:00")));
  CHECK(weekend.open_at(at(kMon, "11:00")));
  CHECK_FALSE(weekend.open_at(at(kTue, "11:00")));
  CHECK(weekend.closed_until(at(kMon, "12:00")) == "closed until Sat 10:00");
  const OpeningHours all = OpeningHours::parse("00:00-24:00");
  CHECK(all.open_at(at(kWed, "00:00")));
  CHECK(all.open_at(at(kWed, "23:59", 59)));
  CHECK(OpeningHours().always_open());
  CHECK(OpeningHours().open_at(at(kWed, "03:00")));
}

TEST_CASE("bad opening hours say what is wrong") {
  CHECK(error_of("9:30-18:00") == "'9:30' is not a time (HH:MM, 00:00 to 23:59)");
  CHECK(error_of("09:30-25:00") == "'25:00' is not a time of day (00:00 to 24:00)");
  CHECK(error_of("24:00-06:00") == "'24:00' is not a time of day (00:00 to 23:59)");
  CHECK(error_of("09:60-18:00") == "'09:60' is not a time of day (00:00 to 23:59)");
  CHECK(error_of("09:30") .find("is not a period") != std::string::npos);
  CHECK(error_of("10:00-10:00") == "'10:00-10:00' opens and closes at the same time (all day: 00:00-24:00)");
  CHECK(error_of("Mo-Fr 09:00-17:00") == "'Mo' is not a day (Mon, Tue, Wed, Thu, Fri, Sat, Sun)");
  CHECK(error_of("09:00-12:00,") == "an empty period (two commas, or a comma at an end)");
  CHECK(error_of("  ").rfind("empty", 0) == 0);
  CHECK_THROWS_AS(parse_clock("3:00"), std::invalid_argument);
  CHECK_THROWS_AS(parse_clock("03:00 "), std::invalid_argument);
  CHECK(parse_clock("03:00") == 3 * 3600);
  CHECK(parse_clock("24:00", true) == 86400);
}

TEST_CASE("the nightly restart fires once per passage of its time, whatever the tick") {
  const int three = parse_clock("03:00");
  // Ticks of 20 ms (here: whole seconds) through the minute: exactly one reading pair contains 03:00.
  int fired = 0;
  LocalTime prev = at(kWed, "02:59", 50);
  for (int i = 1; i <= 120; ++i) {  // 02:59:50 to 03:01:50
    const LocalTime now = advance(at(kWed, "02:59", 50), i);
    fired += passes(prev, now, three) ? 1 : 0;
    prev = now;
  }
  CHECK(fired == 1);
  // A reading exactly at 03:00 fires; the next, still in 03:00's minute, does not again.
  CHECK(passes(at(kWed, "02:59", 59), at(kWed, "03:00"), three));
  CHECK_FALSE(passes(at(kWed, "03:00"), at(kWed, "03:00", 1), three));
  CHECK_FALSE(passes(at(kWed, "03:00", 1), at(kWed, "03:00", 59), three));
  // A launcher started at 03:00:30 (its first reading) does not restart what it just started.
  CHECK_FALSE(passes(at(kWed, "03:00", 30), at(kWed, "03:00", 30), three));
  // Coarse readings (a test clock 30 times faster) still fire once: the interval contains it.
  CHECK(passes(at(kWed, "02:59", 45), at(kWed, "03:00", 15), three));
  // Over midnight.
  CHECK(passes(at(kTue, "23:59", 59), at(kWed, "00:00"), 0));
  CHECK_FALSE(passes(at(kTue, "23:59", 58), at(kTue, "23:59", 59), 0));
  // The clock set by hours (NTP at boot, by hand) is not time passing: nothing fires.
  CHECK_FALSE(passes(at(kWed, "01:00"), at(kWed, "05:00"), three));
  // Clocks forward (02:00 -> 03:00, DST-free: the wall clock just steps an hour): still fires, once.
  CHECK(passes(at(kSun, "01:59", 59), at(kSun, "03:00"), parse_clock("02:30")));
  CHECK(passes(at(kSun, "01:59", 59), at(kSun, "03:00"), three));
  // Clocks back (03:00 -> 02:00) read as a week's jump: fires nothing at that step.
  CHECK_FALSE(passes(at(kSun, "02:59", 59), at(kSun, "02:00"), three));
}

TEST_CASE("a restart time inside the closed hours: the clock passes it while closed") {
  // The launcher restarts whatever runs then (the logger, the modules kept for the closed board);
  // the closed modules start afresh at opening anyway.
  const OpeningHours h = OpeningHours::parse("09:30-18:00");
  const int three = parse_clock("03:00");
  CHECK_FALSE(h.open_at(at(kWed, "03:00")));
  CHECK(passes(at(kWed, "02:59", 59), at(kWed, "03:00"), three));
  // A restart time inside the opening hours fires while open, too.
  CHECK(h.open_at(at(kWed, "13:00")));
  CHECK(passes(at(kWed, "12:59", 59), at(kWed, "13:00"), parse_clock("13:00")));
}

TEST_CASE("the local clock of the week") {
  CHECK(seconds_from(at(kSun, "23:00"), at(kMon, "01:00")) == 7200);
  CHECK(seconds_from(at(kMon, "01:00"), at(kMon, "01:00")) == 0);
  const LocalTime t = advance(at(kSun, "23:59", 59), 1);
  CHECK(t.weekday == kMon);
  CHECK(t.second == 0);
  CHECK(advance(at(kMon, "00:00"), -1).weekday == kSun);
  CHECK(clock_text(parse_clock("09:05")) == "09:05");
  CHECK(weekday_name(kTue) == "Tue");
  const LocalTime now = local_time_of(0);  // whatever the zone: a valid moment of the week
  CHECK(now.weekday >= 0);
  CHECK(now.weekday < 7);
  CHECK(now.second >= 0);
  CHECK(now.second < 86400);
}

TEST_CASE("the test clock: a start time, a day and a speed") {
  TestClock c = parse_test_clock("Wed 09:59:30 x30");
  CHECK(c.start.weekday == kWed);
  CHECK(c.start.second == parse_clock("09:59") + 30);
  CHECK(c.speed == 30);
  c = parse_test_clock("17:59:55");
  CHECK(c.speed == 1);
  CHECK(c.start.second == parse_clock("17:59") + 55);
  CHECK_THROWS_AS(parse_test_clock("17:59"), std::invalid_argument);
  CHECK_THROWS_AS(parse_test_clock("Xyz 17:59:00"), std::invalid_argument);
  CHECK_THROWS_AS(parse_test_clock("17:59:00 x0"), std::invalid_argument);
  CHECK_THROWS_AS(parse_test_clock("17:59:00 xfast"), std::invalid_argument);
}

TEST_CASE("a profile's opening hours and nightly restart, and their mistakes with the line") {
  const Profile p = parse_profile(R"({
  "opening_hours": "09:30-18:00",
  "nightly_restart": "03:00",
  "multicast_route": "eth0",
  "modules": [{"name": "a", "command": ["x"]}, {"name": "b", "command": ["y"], "when_closed": "run"}]
})", "p");
  CHECK(p.opening_hours.text() == "09:30-18:00");
  CHECK(p.nightly_restart == 3 * 3600);
  CHECK(p.multicast_route == "eth0");
  CHECK_FALSE(p.modules[0].run_when_closed);
  CHECK(p.modules[1].run_when_closed);
  const Profile plain = parse_profile(R"({"modules": [{"name": "a", "command": ["x"]}]})", "p");
  CHECK(plain.opening_hours.always_open());
  CHECK(plain.nightly_restart == -1);
  CHECK(plain.multicast_route.empty());

  CHECK(profile_error("{\n  \"modules\": [{\"name\": \"a\", \"command\": [\"x\"]}],\n  \"opening_hours\": \"9:30-18:00\"\n}") ==
        "profile p line 3: 'opening_hours' \"9:30-18:00\": '9:30' is not a time (HH:MM, 00:00 to 23:59)");
  CHECK(profile_error("{\"modules\": [{\"name\": \"a\", \"command\": [\"x\"]}],\n\n\n \"nightly_restart\": \"3am\"}") ==
        "profile p line 4: 'nightly_restart': '3am' is not a time (HH:MM, 00:00 to 23:59)");
  CHECK(profile_error("{\"modules\": [{\"name\": \"a\", \"command\": [\"x\"]}], \"nightly_restart\": 3}") ==
        "profile p line 1: 'nightly_restart' must be a time of day such as \"03:00\"");
  CHECK(profile_error("{\"modules\": [{\"name\": \"a\", \"command\": [\"x\"]}], \"opening_hours\": \"10:00-10:00\"}")
            .find("opens and closes at the same time") != std::string::npos);
  CHECK(profile_error("{\"modules\": [{\"name\": \"a\", \"command\": [\"x\"], \"when_closed\": \"keep\"}]}")
            .find("'when_closed' must be \"stop\"") != std::string::npos);
  CHECK(profile_error("{\"modules\": [{\"name\": \"a\", \"command\": [\"x\"]}], \"multicast_route\": \"\"}")
            .find("'multicast_route' must be an interface name") != std::string::npos);
}
