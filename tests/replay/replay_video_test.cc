// bricklayer-replay --video on a camera run recorded from the real simcam, vision and prediction nodes:
// a real video file that OpenCV's reader (FFmpeg) opens, with the expected number of frames and
// duration, whose frame at a known time shows the known stack (the real detector finds the scenario's
// blocks in the camera half, where they stood).
#include <catch2/catch.hpp>

#include <regex>

#include <opencv2/videoio.hpp>

#include "bricklayer/common/channels.h"
#include "bricklayer/detection/detector.h"
#include "bricklayer/runtime/log_file.h"
#include "bricklayer/replay/video_render.h"
#include "harness/program.h"
#include "harness/scratch.h"
#include "replay_fixture.h"

using namespace bricklayer;

namespace {
const std::string kScenario = std::string(BRICKLAYER_SOURCE_DIR) + "/launch/scenarios/build-4-optimum.json";
}  // namespace

TEST_CASE("a recorded run renders to a video with its frames, its duration and the stack at a known time") {
  harness::ScratchDir dir("replay-video");
  const std::string log = (dir / "camera.lcm").string();
  // 300 frames at 30 frames a second: 10 s; build-4-optimum has 4 blocks from 8 s on.
  test::record_camera_run(log, kScenario, 300);
  const std::string out = (dir / "moment.mp4").string();
  const auto r = harness::run_program("bricklayer-replay", {log, "--video", out, "--from", "+5", "--no-progress"},
                                      std::chrono::seconds(120));
  INFO(r.out << r.err);
  REQUIRE(r.status.clean());
  CHECK(r.out.find("wrote " + out + ": ") != std::string::npos);

  cv::VideoCapture video(out);
  REQUIRE(video.isOpened());
  const double fps = video.get(cv::CAP_PROP_FPS);
  const auto frames = static_cast<int64_t>(video.get(cv::CAP_PROP_FRAME_COUNT));
  CHECK(fps == Approx(30).margin(0.01));
  // From 5 s into the log to its last frame: about 150 camera frames (as the log holds them), one video
  // frame each at the recorded pace.
  int64_t expected = 0, first = -1;
  {
    runtime::LogReader reader(log);
    runtime::LogEvent e;
    while (reader.next(e)) {
      if (first < 0) first = e.utime;
      expected += e.channel == channel(kImageChannel) && e.utime >= first + 5'000'000;
    }
  }
  CHECK(expected >= 148);
  CHECK(frames == expected);
  CHECK(frames / fps == Approx(static_cast<double>(expected) / 30).margin(0.001));
  // The frame at about 9 s into the log (4 s into the video): the camera half shows the 4 blocks.
  video.set(cv::CAP_PROP_POS_FRAMES, 120);
  cv::Mat picture;
  REQUIRE(video.read(picture));
  REQUIRE(picture.cols == 2 * replay::VideoRenderer::kSideWidth);
  REQUIRE(picture.rows == replay::VideoRenderer::kSideHeight + replay::VideoRenderer::kStripHeight);
  const cv::Mat camera = picture(cv::Rect(0, 0, replay::VideoRenderer::kSideWidth, replay::VideoRenderer::kSideHeight)).clone();
  detection::Detector detector{BoardGeometry{}};
  const auto found = detector.detect(camera);
  REQUIRE(found.status == detection::Detection::kOk);
  CHECK(found.blocks.size() == 4);
  // The strip is drawn (white text on dark grey), the projector side is black (no projector in this run).
  const cv::Mat strip = picture(cv::Rect(0, replay::VideoRenderer::kSideHeight, picture.cols, replay::VideoRenderer::kStripHeight));
  double brightest = 0;
  cv::minMaxLoc(strip, nullptr, &brightest);
  CHECK(brightest > 200);
}

TEST_CASE("a video of a range without camera frames is a clear error") {
  harness::ScratchDir dir("replay-video-empty");
  const std::string log = (dir / "stacks.lcm").string();
  test::record_run(log, test::demo_stacks(30));
  const auto r = harness::run_program("bricklayer-replay", {log, "--video", (dir / "x.mp4").string(), "--no-progress"},
                                      std::chrono::seconds(60));
  CHECK(r.status.code == 1);
  CHECK(r.err.find("no camera frame in the range") != std::string::npos);
}
