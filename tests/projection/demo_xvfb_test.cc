// NETNS + Xvfb, real processes, end to end: the shipped demo profile with a display (projection in a
// real X window on a virtual X server) runs, and the projector image it presents while the scenario
// shows the 4-block optimum has every block of that stack lit blue where the scenario put it, and no
// green anywhere. The test watches the snapshots for that moment (the scenario loops) instead of
// sampling one wall-clock instant, which a loaded machine reaches late.
#include <catch2/catch.hpp>

#include <signal.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <sstream>

#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include "bricklayer/board/board_geometry.h"
#include "bricklayer/launcher/process.h"
#include "harness/scratch.h"

using namespace bricklayer;
using namespace std::chrono_literals;
namespace fs = std::filesystem;

namespace {
std::string slurp(const fs::path& p) {
  std::ifstream in(p);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}
// Projector pixel of board point (x block lengths from the edge, y block lengths above the surface) in
// the uncalibrated default setup the demo runs with (board.h).
cv::Point projector_px(double x, double y) {
  BoardGeometry g;
  return {static_cast<int>(kDefaultCameraToProjector[0] * g.to_px_x(x)),
          static_cast<int>(kDefaultCameraToProjector[4] * g.to_px_y(y))};
}

// The optimum of launch/scenarios/build-4-optimum.json (rows, left ends), block height 1/3.
const std::vector<std::pair<int, double>> kOptimum = {
    {0, -0.47855339059439}, {1, -1.15621108509884}, {1, 0.16789321881360}, {2, -0.53312874311984}};

bool optimum_lit_blue(const cv::Mat& shot) {
  if (shot.empty() || shot.cols != kDefaultProjectorWidth) return false;
  for (const auto& [row, x] : kOptimum) {
    const cv::Vec3b bgr = shot.at<cv::Vec3b>(projector_px(x + 0.5, (row + 0.5) / 3.0));
    if (bgr[0] <= 150 || bgr[2] >= 60) return false;
  }
  return true;
}
}  // namespace

TEST_CASE("the demo under Xvfb lights the scenario's optimum stack blue where its blocks are") {
  harness::ScratchDir dir("xvfb-demo");
  const std::string display = ":" + std::to_string(100 + ::getpid() % 800);
  launcher::SpawnOptions xo;
  xo.stdout_path = (dir / "xvfb.out").string();
  xo.stderr_path = (dir / "xvfb.err").string();
  auto xvfb = launcher::Process::spawn({"/usr/bin/Xvfb", display, "-screen", "0", "1280x800x24", "-nolisten", "tcp"}, xo);
  for (int i = 0; i < 100 && !fs::exists("/tmp/.X11-unix/X" + display.substr(1)); ++i) usleep(50000);
  REQUIRE(fs::exists("/tmp/.X11-unix/X" + display.substr(1)));

  // The shipped profile; the windowed projection also writes its frames to a snapshot folder.
  nlohmann::json profile = nlohmann::json::parse(slurp(std::string(BRICKLAYER_SOURCE_DIR) + "/launch/profiles/demo.json"));
  profile["logger"]["file"] = (dir / "demo").string();
  for (auto& m : profile["modules"]) {
    if (m["name"] == "projection") {
      m["command_with_display"] = {"bricklayer-projection", "--window", "--renderer", "software", "--snapshot-dir",
                                   (dir / "snapshots").string(), "--snapshot-every", "0.5"};
    }
  }
  std::ofstream(dir / "demo.json") << profile.dump(1);

  launcher::SpawnOptions o;
  o.stdout_path = (dir / "launch.out").string();
  o.stderr_path = (dir / "launch.err").string();
  o.env = {"DISPLAY=" + display, "SDL_AUDIODRIVER=dummy", "LCM_DEFAULT_URL=udpm://239.255.76.67:7667?ttl=0"};
  // build-4-optimum shows the balanced optimum from 11 s to 15 s of scenario time, and the demo loops
  // it: watch the snapshots (every 0.5 s) until one shows it, for at most 75 s.
  auto launch = launcher::Process::spawn(
      {harness::program_path("bricklayer-launch"), "--root", BRICKLAYER_SOURCE_DIR, "--duration", "90", (dir / "demo.json").string()}, o);
  cv::Mat shot;
  const auto give_up = std::chrono::steady_clock::now() + 75s;
  while (launch.running() && std::chrono::steady_clock::now() < give_up) {
    usleep(200000);
    const cv::Mat latest = cv::imread((dir / "snapshots" / "latest.png").string(), cv::IMREAD_COLOR);
    if (optimum_lit_blue(latest)) {
      shot = latest;
      break;
    }
    if (!latest.empty()) shot = latest;
  }
  const bool was_running = launch.running();
  launch.signal(SIGTERM);
  auto st = launch.wait_for(30s);
  xvfb.signal(SIGTERM);
  REQUIRE(st);
  std::string out = slurp(dir / "launch.out");
  INFO(out << slurp(dir / "launch.err"));
  CHECK(was_running);
  CHECK(st->clean());
  CHECK(out.find("all 5 processes of profile demo are up") != std::string::npos);
  CHECK(out.find("died") == std::string::npos);

  REQUIRE_FALSE(shot.empty());
  REQUIRE(shot.cols == kDefaultProjectorWidth);
  for (const auto& [row, x] : kOptimum) {
    const cv::Point c = projector_px(x + 0.5, (row + 0.5) / 3.0);
    const cv::Vec3b bgr = shot.at<cv::Vec3b>(c);
    INFO("block row " << row << " x " << x << " at projector " << c << ": BGR " << bgr);
    CHECK(bgr[0] > 150);  // blue: balanced
    CHECK(bgr[2] < 60);   // not red
  }
  // Empty board beside the pile stays dark.
  cv::Vec3b empty = shot.at<cv::Vec3b>(projector_px(3.0, 1.5));
  CHECK(empty[0] < 40);
  CHECK(empty[2] < 40);
  // Green is never lit in the game display (the camera measures in green).
  std::vector<cv::Mat> channels;
  cv::split(shot, channels);
  CHECK(cv::countNonZero(channels[1]) == 0);
}
