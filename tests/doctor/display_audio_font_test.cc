// The display, audio and font checks of the real bricklayer-doctor: under Xvfb (a real X server with
// one screen of a chosen size) and with no display at all; SDL's audio drivers that reach no speaker;
// the shipped font and a missing one.
#include <catch2/catch.hpp>

#include <filesystem>
#include <memory>

#include "doctor_test_util.h"
#include "harness/program.h"

using namespace bricklayer;
using test::check_line;
using test::run_doctor;
using test::severity;
namespace fs = std::filesystem;

namespace {

// An Xvfb server on a display of its own for the test's lifetime.
class Xvfb {
 public:
  explicit Xvfb(const std::string& screen, int offset) : display_(":" + std::to_string(200 + (getpid() * 7 + offset) % 700)) {
    server_ = std::make_unique<harness::Program>("/usr/bin/Xvfb",
                                                 std::vector<std::string>{display_, "-screen", "0", screen, "-nolisten", "tcp"});
    for (int i = 0; i < 200 && !fs::exists(socket()); ++i) usleep(25000);
  }
  bool up() const { return fs::exists(socket()); }
  std::string env() const { return "DISPLAY=" + display_; }

 private:
  std::string socket() const { return "/tmp/.X11-unix/X" + display_.substr(1); }
  std::string display_;
  std::unique_ptr<harness::Program> server_;  // stopped when the test ends
};

const std::vector<std::string> kNoSdlOverride = {"SDL_VIDEODRIVER=", "WAYLAND_DISPLAY="};

std::vector<std::string> with(std::vector<std::string> env, const std::string& more) {
  env.push_back(more);
  return env;
}

}  // namespace

TEST_CASE("under Xvfb: display 1 of a one-screen server fails, display 0 reports its resolution") {
  Xvfb x("1280x720x24", 1);
  REQUIRE(x.up());
  auto env = with(kNoSdlOverride, x.env());
  auto r = run_doctor({"all-in-one", "--checks", "display"}, env);
  INFO(r.out);
  const std::string line = check_line(r.out, "display");
  CHECK(severity(line) == "FAILED");
  CHECK(line.find("projection wants display 1, 1 display (0: 1280x720") != std::string::npos);
  CHECK(line.find("fix: connect the projector and extend the desktop") != std::string::npos);
  CHECK(r.code == 1);

  // projector-host fills display 0: present, but not the 1024x768 projection draws.
  r = run_doctor({"projector-host", "--checks", "display"}, env);
  INFO(r.out);
  CHECK(severity(check_line(r.out, "display")) == "warning");
  CHECK(check_line(r.out, "display").find("display 0 is 1280x720") != std::string::npos);
  CHECK(r.code == 0);
}

TEST_CASE("under Xvfb at the projection's size: display ok") {
  Xvfb x("1024x768x24", 2);
  REQUIRE(x.up());
  auto r = run_doctor({"projector-host", "--checks", "display"}, with(kNoSdlOverride, x.env()));
  INFO(r.out);
  CHECK(check_line(r.out, "display").find("ok       display              display 0 is 1024x768") == 0);
  CHECK(r.code == 0);
}

TEST_CASE("with no display: a projector profile fails, the demo's window only warns, offscreen does not count") {
  auto none = with(kNoSdlOverride, "DISPLAY=");
  auto r = run_doctor({"all-in-one", "--checks", "display"}, none);
  INFO(r.out);
  CHECK(severity(check_line(r.out, "display")) == "FAILED");
  CHECK(check_line(r.out, "display").find("no display server") != std::string::npos);
  CHECK(r.code == 1);
  r = run_doctor({"demo", "--checks", "display"}, none);
  CHECK(severity(check_line(r.out, "display")) == "warning");
  CHECK(r.code == 0);
  r = run_doctor({"all-in-one", "--checks", "display"}, {"DISPLAY=:0", "SDL_VIDEODRIVER=offscreen"});
  CHECK(check_line(r.out, "display").find("SDL_VIDEODRIVER=offscreen shows nothing") != std::string::npos);
  CHECK(r.code == 1);
  // The camera host projects nothing.
  CHECK(severity(check_line(run_doctor({"camera-host", "--checks", "display"}, none).out, "display")) == "ok");
}

TEST_CASE("audio: SDL's dummy and disk drivers and a driver that cannot open warn, --mute needs none") {
  auto dir = test::temp_dir("audio");
  for (const char* driver : {"dummy", "disk"}) {
    auto r = run_doctor({"all-in-one", "--checks", "audio"},
                        {std::string("SDL_AUDIODRIVER=") + driver, "SDL_DISKAUDIOFILE=" + (dir / "out.raw").string()});
    INFO(r.out);
    CHECK(check_line(r.out, "audio").find(std::string("SDL's ") + driver + " audio driver: the beep reaches no speaker") != std::string::npos);
    CHECK(r.code == 0);  // a silent exhibit still runs
  }
  auto r = run_doctor({"all-in-one", "--checks", "audio"}, {"SDL_AUDIODRIVER=nosuchdriver"});
  INFO(r.out);
  CHECK(severity(check_line(r.out, "audio")) == "warning");
  CHECK(check_line(r.out, "audio").find("the exhibit would not beep") != std::string::npos);
  const std::string muted = test::write_file(
      dir / "muted.json", R"({"modules":[{"name":"projection","command":["bricklayer-projection","--headless","--mute"]}]})");
  r = run_doctor({muted, "--checks", "audio"}, {"SDL_AUDIODRIVER=nosuchdriver"});
  CHECK(check_line(r.out, "audio").find("ok       audio                projection runs with --mute") == 0);
  fs::remove_all(dir);
}

TEST_CASE("fonts: the shipped default loads, a missing font fails, since projection would stop") {
  auto r = run_doctor({"all-in-one", "--checks", "fonts"});
  INFO(r.out);
  CHECK(check_line(r.out, "fonts").find("ok       fonts                /usr/share/fonts/truetype/dejavu/DejaVuSans-Bold.ttf (DejaVu Sans Bold)") == 0);
  CHECK(r.code == 0);
  auto dir = test::temp_dir("fonts");
  const std::string bad = test::write_file(
      dir / "bad-font.json",
      R"({"modules":[{"name":"projection","command":["bricklayer-projection","--headless","--font","/nonexistent/Sans.ttf"]}]})");
  r = run_doctor({bad, "--checks", "fonts"});
  INFO(r.out);
  CHECK(severity(check_line(r.out, "fonts")) == "FAILED");
  CHECK(check_line(r.out, "fonts").find("install fonts-dejavu-core") != std::string::npos);
  CHECK(r.code == 1);
  fs::remove_all(dir);
}
