// bricklayer-calibrate as a real process on a real LCM bus (NETNS: a private network namespace).
// The test plays projector and camera: it shows every commanded pattern (render_pattern), echoes the
// command's sequence on BL_PROJECTOR, and streams camera frames rendered by simcam through a random
// setup as JPEG on BL_IMAGE. The process must calibrate within tolerance, save and publish; then the
// self-check must pass for the same camera and fail (exit 3) for a moved one.
#include <catch2/catch.hpp>

#include <opencv2/imgcodecs.hpp>

#include <fcntl.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <functional>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "bricklayer/board/calibration_file.h"
#include "bricklayer/board/mapping.h"
#include "bricklayer/patterns/patterns.h"
#include "bricklayer/calibration_t.hpp"
#include "bricklayer/command_t.hpp"
#include "bricklayer/common/channels.h"
#include "bricklayer/heartbeat_t.hpp"
#include "bricklayer/image_t.hpp"
#include "bricklayer/projector_state_t.hpp"
#include "bricklayer/runtime/codec.h"
#include "bricklayer/runtime/lcm_bus.h"
#include "bricklayer/stack_t.hpp"
#include "bricklayer/simcam/render.h"

extern char** environ;

namespace sim = bricklayer::simcam;
using namespace bricklayer;

namespace {

constexpr const char* kUrl = "udpm://239.255.76.67:7667?ttl=0";

struct Child {
  pid_t pid = -1;
  std::string stderr_path;
};

Child spawn(const std::vector<std::string>& args, const std::string& stderr_path) {
  std::vector<char*> argv;
  for (const auto& a : args) argv.push_back(const_cast<char*>(a.c_str()));
  argv.push_back(nullptr);
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, 2, stderr_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  Child c;
  c.stderr_path = stderr_path;
  const int rc = posix_spawn(&c.pid, argv[0], &actions, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  REQUIRE(rc == 0);
  return c;
}

std::string slurp(const std::string& path) {
  std::ifstream in(path);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

// Waits at most limit_s for a child to exit and returns its wait status. A child still running then
// is killed (SIGKILL cannot be caught, so the reaping wait returns at once) and the test fails saying
// so: a process that ignores SIGTERM or hangs must fail its test, not hang the suite.
int wait_child(const Child& child, double limit_s, const char* after) {
  const auto start = std::chrono::steady_clock::now();
  int status = 0;
  while (true) {
    const pid_t r = waitpid(child.pid, &status, WNOHANG);
    if (r == child.pid) return status;
    if (r < 0) FAIL("waitpid(" << child.pid << ") failed: " << std::strerror(errno));
    if (std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count() > limit_s) {
      kill(child.pid, SIGKILL);
      waitpid(child.pid, &status, 0);
      FAIL("child " << child.pid << " (stderr " << child.stderr_path << ") still running " << limit_s << " s " << after
                    << "; killed with SIGKILL; stderr:\n" << slurp(child.stderr_path));
    }
    usleep(10000);
  }
}

// Kills and reaps a child the test did not stop itself (a failed REQUIRE leaves the scope early): a
// --serve process left running would keep the test's output open and hold up ctest.
struct ReapOnExit {
  const Child& child;
  ~ReapOnExit() {
    if (waitpid(child.pid, nullptr, WNOHANG) == 0) {
      kill(child.pid, SIGKILL);
      waitpid(child.pid, nullptr, 0);
    }
  }
};

// SIGTERM, then a bounded wait (the processes stop within a second when idle; 5 s leaves room for a
// loaded machine).
int stop_child(const Child& child, double limit_s = 5) {
  kill(child.pid, SIGTERM);
  return wait_child(child, limit_s, "after SIGTERM");
}

// Projector and camera in one: answers SHOW_PATTERN / CLEAR_PATTERN, streams frames.
class FakeRig {
 public:
  // answer_projector: play the projector too (echo commands). follow_projector: light the scene with
  // what a real bricklayer-projection reports on BL_PROJECTOR instead (closed loop, as simcam does).
  FakeRig(const sim::CameraSetup& camera, const sim::ProjectorSetup& projector, bool answer_projector = true,
          bool follow_projector = false)
      : bus_(kUrl), renderer_(camera, projector), answer_projector_(answer_projector) {
    if (follow_projector) {
      answer_projector_ = false;
      subscribe<projector_state_t>(channel(kProjectorChannel), [this](const projector_state_t& s) { on_projector(s); });
    }
    nuisance_ = sim::Nuisance::level(1);
    nuisance_.layout_seed = 11;
    nuisance_.jpeg_quality = 0;  // the bus encoding below is the JPEG round trip
    subscribe<command_t>(channel(kCommandChannel), [this](const command_t& c) { on_command(c); });
    subscribe<calibration_t>(channel(kCalibrationChannel), [this](const calibration_t& c) { published = c; });
    subscribe<heartbeat_t>(channel(kHeartbeatChannel), [this](const heartbeat_t& h) {
      if (h.module == "calibrate") last_heartbeat = h;
    });
    render_frame();
  }

  // Pumps the bus and streams frames at ~30 Hz until the child exits; returns its exit code.
  int run_until_exit(const Child& child, double limit_s = 45) {
    const auto start = std::chrono::steady_clock::now();
    auto next_frame = start;
    while (true) {
      int status = 0;
      if (waitpid(child.pid, &status, WNOHANG) == child.pid) {
        for (int i = 0; i < 10; ++i) bus_.handle(10);  // the last messages
        return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
      }
      const auto now = std::chrono::steady_clock::now();
      if (std::chrono::duration<double>(now - start).count() > limit_s) {
        kill(child.pid, SIGKILL);
        waitpid(child.pid, &status, 0);
        FAIL("bricklayer-calibrate did not finish within " << limit_s << " s; stderr:\n" << slurp(child.stderr_path));
      }
      if (now >= next_frame) {
        publish_frame();
        next_frame = now + std::chrono::milliseconds(33);
      }
      bus_.handle(5);
    }
  }

  // Pumps the bus and streams frames until done() is true or limit_s passes; returns done().
  bool run_until(const std::function<bool()>& done, double limit_s) {
    const auto start = std::chrono::steady_clock::now();
    auto next_frame = start;
    while (!done()) {
      const auto now = std::chrono::steady_clock::now();
      if (std::chrono::duration<double>(now - start).count() > limit_s) return false;
      if (now >= next_frame) {
        publish_frame();
        next_frame = now + std::chrono::milliseconds(33);
      }
      bus_.handle(5);
    }
    return true;
  }

  void publish_stack(int blocks) {
    bricklayer::stack_t s{};
    s.block_length = 1;
    s.block_height = 1.0 / 3;
    s.status = bricklayer::stack_t::STATUS_OK;
    s.num_blocks = blocks;
    s.blocks.resize(blocks);
    for (int i = 0; i < blocks; ++i) s.blocks[i].id = i;
    publish(channel(kStackChannel), s);
  }

  void send_self_check() {
    command_t c{};
    c.command = command_t::SELF_CHECK;
    c.sequence = 1;
    c.argument = "";
    publish(channel(kCommandChannel), c);
  }

  std::optional<double> heartbeat_value(const std::string& name) const {
    if (!last_heartbeat) return std::nullopt;
    for (int i = 0; i < last_heartbeat->num_values; ++i) {
      if (last_heartbeat->value_names[i] == name) return last_heartbeat->values[i];
    }
    return std::nullopt;
  }

  // Blocks standing on the board in the following frames.
  void set_scene(const core::Stack& scene) {
    scene_ = scene;
    render_frame();
  }

  int corrupt_every = 0;  // > 0: every n-th frame carries garbage instead of a JPEG
  // Every n-th frame shows `scene` instead (a block counted too many or too few now and then).
  void set_other_scene_every(int n, const core::Stack& scene) {
    other_every_ = n;
    const cv::Mat* image = shown_.empty() ? nullptr : &shown_;
    cv::imencode(".jpg", renderer_.render(scene, nuisance_, image, 4321).bgr, other_jpeg_, {cv::IMWRITE_JPEG_QUALITY, 95});
  }

  std::optional<calibration_t> published;
  std::optional<heartbeat_t> last_heartbeat;
  int patterns_shown = 0;

 private:
  void on_projector(const projector_state_t& s) {
    cv::Mat image = cv::imdecode(s.image.data, cv::IMREAD_COLOR);
    if (image.empty()) return;
    shown_ = image;
    if (s.mode == projector_state_t::MODE_PATTERN) ++patterns_shown;
    render_frame();
  }

  void on_command(const command_t& c) {
    if (!answer_projector_) return;
    if (c.command == command_t::SHOW_PATTERN) {
      shown_ = patterns::render_pattern(c, renderer_.projector().size);
      ++patterns_shown;
    } else if (c.command == command_t::CLEAR_PATTERN) {
      shown_ = cv::Mat(renderer_.projector().size, CV_8UC3, cv::Scalar(40, 40, 40));
    } else {
      return;
    }
    render_frame();
    if (!answer_projector_) return;
    projector_state_t s{};
    s.utime = bus_.now_utime();
    s.frame_number = -1;
    s.command_sequence = c.sequence;
    s.mode = projector_state_t::MODE_PATTERN;
    s.image.source = "fakerig";
    publish(channel(kProjectorChannel), s);
  }

  void render_frame() {
    const cv::Mat* image = shown_.empty() ? nullptr : &shown_;
    const cv::Mat bgr = renderer_.render(scene_, nuisance_, image, 1234).bgr;
    cv::imencode(".jpg", bgr, jpeg_, {cv::IMWRITE_JPEG_QUALITY, 95});
    size_ = bgr.size();
  }

  void publish_frame() {
    image_t img{};
    img.utime = bus_.now_utime();
    img.frame_number = frame_number_++;
    img.width = size_.width;
    img.height = size_.height;
    img.format = image_t::FORMAT_JPEG;
    img.source = "fakerig";
    img.data = other_every_ > 0 && img.frame_number % other_every_ == 1 ? other_jpeg_ : jpeg_;
    if (corrupt_every > 0 && img.frame_number % corrupt_every == 0) {
      img.data.assign(img.data.size() / 2, 0x5A);  // not a JPEG
    }
    img.size = static_cast<int32_t>(img.data.size());
    publish(channel(kImageChannel), img);
  }

  // Every message of type T on the channel, decoded (a message that does not decode is skipped).
  template <typename T>
  void subscribe(const std::string& name, std::function<void(const T&)> handler) {
    bus_.subscribe(name, runtime::QueuePolicy::keep(1000), [handler = std::move(handler)](const runtime::Received& r) {
      if (const std::optional<T> m = runtime::decode<T>(r.data, r.size)) handler(*m);
    });
  }
  template <typename T>
  void publish(const std::string& name, const T& msg) {
    const std::vector<uint8_t> bytes = runtime::encode(msg);
    bus_.publish(name, bytes.data(), bytes.size());
  }

  runtime::LcmBus bus_;
  sim::Renderer renderer_;
  bool answer_projector_;
  sim::Nuisance nuisance_;
  core::Stack scene_;
  cv::Mat shown_;
  std::vector<uint8_t> jpeg_;
  std::vector<uint8_t> other_jpeg_;
  int other_every_ = 0;
  cv::Size size_;
  int64_t frame_number_ = 0;
};

std::string program() { return std::string(BRICKLAYER_BINARY_DIR) + "/bin/bricklayer-calibrate"; }
std::string temp(const std::string& name) { return "/tmp/bl-calibrate-test-" + std::to_string(getpid()) + "-" + name; }

double max_mapping_error(const calibration_t& c, const sim::CameraSetup& camera, const sim::ProjectorSetup& projector) {
  double worst = 0;
  for (double y = 10; y <= 470; y += 20) {
    for (double x = 10; x <= 630; x += 20) {
      const cv::Point2d p = sim::rectified_to_camera(camera, {x, y});
      if (p.x < 2 || p.y < 2 || p.x > camera.size.width - 3 || p.y > camera.size.height - 3) continue;
      worst = std::max(worst, cv::norm(board::camera_to_projector(c, p) - sim::camera_to_projector(camera, projector, p)));
    }
  }
  return worst;
}

}  // namespace

TEST_CASE("bricklayer-calibrate calibrates over the bus, saves, publishes, and its self-check catches a moved camera") {
  const uint64_t seed = 4;
  const sim::CameraSetup camera = sim::CameraSetup::random(seed);
  const sim::ProjectorSetup projector = sim::ProjectorSetup::random(seed);
  const std::string output = temp("calibration.json");
  std::remove(output.c_str());

  {
    FakeRig rig(camera, projector);
    rig.corrupt_every = 3;  // undecodable frames are counted errors; calibration waits for the next one
    const Child child = spawn({program(), "--lcm-url", kUrl, "--output", output, "--timeout", "3"}, temp("calibrate.err"));
    const ReapOnExit reap_child{child};
    const int code = rig.run_until_exit(child);
    const std::string log = slurp(child.stderr_path);
    INFO(log);
    REQUIRE(code == 0);
    CHECK(rig.patterns_shown == 6);
    CHECK(log.find("step 6 of 6") != std::string::npos);
    CHECK(log.find("calibration ok") != std::string::npos);
    CHECK(log.find("could not be decoded") != std::string::npos);
    REQUIRE(rig.published.has_value());
    const calibration_t saved = board::load_calibration(output);
    CHECK(saved.utime == rig.published->utime);
    const double worst = max_mapping_error(saved, camera, projector);
    INFO("max mapping error " << worst);
    CHECK(worst < 1.5);
  }
  {
    FakeRig rig(camera, projector);
    const Child child = spawn({program(), "--lcm-url", kUrl, "--output", output, "--self-check"}, temp("check.err"));
    const ReapOnExit reap_child{child};
    const int code = rig.run_until_exit(child);
    INFO(slurp(child.stderr_path));
    CHECK(code == 0);
    REQUIRE(rig.last_heartbeat.has_value());
    bool found = false;
    for (int i = 0; i < rig.last_heartbeat->num_values; ++i) {
      if (rig.last_heartbeat->value_names[i] == "drift_px") {
        found = true;
        CHECK(rig.last_heartbeat->values[i] < 1.0);
      }
    }
    CHECK(found);
  }
  {
    // --serve: publishes the saved calibration, self-checks on command only when the board is empty.
    sim::CameraSetup moved = camera;
    moved.rectified_to_camera = cv::Matx33d(1, 0, -4, 0, 1, 4, 0, 0, 1) * camera.rectified_to_camera;
    FakeRig rig(moved, projector);
    const Child child = spawn({program(), "--lcm-url", kUrl, "--output", output, "--serve"}, temp("serve.err"));
    const ReapOnExit reap_child{child};
    CHECK(rig.run_until([&] { return rig.published.has_value(); }, 10));
    rig.publish_stack(3);
    rig.run_until([] { return false; }, 0.3);
    rig.send_self_check();
    rig.run_until([] { return false; }, 1.5);
    CHECK(rig.patterns_shown == 0);  // not with blocks on the board
    rig.publish_stack(0);
    rig.run_until([] { return false; }, 0.3);
    rig.send_self_check();
    const bool measured = rig.run_until([&] { return rig.heartbeat_value("drift_px").has_value(); }, 10);
    const int status = stop_child(child);
    const std::string log = slurp(child.stderr_path);
    INFO(log);
    CHECK(measured);
    CHECK(rig.patterns_shown == 1);
    CHECK(rig.heartbeat_value("drift_px").value_or(0) > 3.0);
    CHECK(log.find("board is not empty") != std::string::npos);
    CHECK(log.find("has moved") != std::string::npos);
    CHECK(WIFEXITED(status));
    CHECK(WEXITSTATUS(status) == 0);
  }
  {
    // --serve --self-check-every: checks by itself once the board has stayed empty.
    FakeRig rig(camera, projector);
    const Child child = spawn({program(), "--lcm-url", kUrl, "--output", output, "--serve", "--self-check-every", "60",
                               "--empty-for", "0.5"},
                              temp("auto.err"));
    const ReapOnExit reap_child{child};
    rig.run_until([&] { return rig.published.has_value(); }, 10);
    rig.publish_stack(0);
    const bool measured = rig.run_until([&] { return rig.heartbeat_value("drift_px").has_value(); }, 10);
    const int status = stop_child(child);
    INFO(slurp(child.stderr_path));
    CHECK(measured);
    CHECK(rig.patterns_shown == 1);
    CHECK(rig.heartbeat_value("drift_px").value_or(99) < 1.0);
  }
  {
    sim::CameraSetup moved = camera;
    moved.rectified_to_camera = cv::Matx33d(1, 0, 5, 0, 1, -3, 0, 0, 1) * camera.rectified_to_camera;
    FakeRig rig(moved, projector);
    const Child child = spawn({program(), "--lcm-url", kUrl, "--output", output, "--self-check"}, temp("moved.err"));
    const ReapOnExit reap_child{child};
    const int code = rig.run_until_exit(child);
    const std::string log = slurp(child.stderr_path);
    INFO(log);
    CHECK(code == 3);
    CHECK(log.find("has moved") != std::string::npos);
  }
  std::remove(output.c_str());
}

// Where the camera sees board point (x, 0.2) (block lengths) according to a calibration: its board x.
double calibrated_x(const calibration_t& c, const sim::CameraSetup& camera, double x, double y = 0.2) {
  const BoardGeometry& g = camera.board;
  const cv::Point2d p = sim::rectified_to_camera(camera, {g.to_px_x(x), g.to_px_y(y)});
  return board::camera_to_board(c, p).x;
}

TEST_CASE("bricklayer-calibrate --scale-from-blocks corrects the board scale of a projector mounted larger than nominal") {
  const uint64_t seed = 6;
  const sim::CameraSetup camera = sim::CameraSetup::random(seed);
  sim::ProjectorSetup projector = sim::ProjectorSetup::random(seed);
  // Each projector pixel covers 10% more board than the nominal mounting assumes (about the view's centre).
  const cv::Matx33d larger(1.1, 0, -0.1 * 320, 0, 1.1, -0.1 * 240, 0, 0, 1);
  projector.projector_to_rectified = larger * projector.projector_to_rectified;
  const std::string output = temp("scaled.json");
  std::remove(output.c_str());
  {
    FakeRig rig(camera, projector);
    const Child child = spawn({program(), "--lcm-url", kUrl, "--output", output, "--timeout", "3"}, temp("scaled-cal.err"));
    const ReapOnExit reap_child{child};
    const int code = rig.run_until_exit(child);
    INFO(slurp(child.stderr_path));
    REQUIRE(code == 0);
  }
  const calibration_t before = board::load_calibration(output);
  INFO("board x of true x = 3 before: " << calibrated_x(before, camera, 3.0));
  CHECK(std::abs(calibrated_x(before, camera, 3.0) - 3.0) > 0.2);  // the projector's scale error

  core::Stack blocks;  // four blocks standing apart on the bottom row, one on top
  blocks.blocks = {{1, 0, -3.4}, {2, 0, -1.9}, {3, 0, -0.6}, {4, 0, 0.7}, {5, 1, -3.1}};
  {
    FakeRig rig(camera, projector);
    rig.set_scene(blocks);
    rig.corrupt_every = 4;  // undecodable frames are counted and skipped
    core::Stack five = blocks;  // every third frame counts a fifth block: left out, the count most frames agree on is 4
    five.blocks.push_back({6, 0, -4.9});
    rig.set_other_scene_every(3, five);
    const Child child = spawn({program(), "--lcm-url", kUrl, "--output", output, "--scale-from-blocks"}, temp("scale.err"));
    const ReapOnExit reap_child{child};
    const int code = rig.run_until_exit(child);
    const std::string log = slurp(child.stderr_path);
    INFO(log);
    REQUIRE(code == 0);
    CHECK(log.find("board scale corrected") != std::string::npos);
    CHECK(log.find("could not be decoded") != std::string::npos);
    CHECK(log.find("that count 4") != std::string::npos);
    REQUIRE(rig.published.has_value());
    const calibration_t after = board::load_calibration(output);
    CHECK(after.utime == rig.published->utime);
    for (double x : {-3.0, -1.0, 0.0, 1.0, 2.0, 3.0}) {
      INFO("x " << x);
      CHECK(calibrated_x(after, camera, x) == Approx(x).margin(0.01));
    }
    // Up the board too: the lean of the end lines corrected the frame's vertical. Compared with the
    // correction along the board alone (the same fit without its shear and vertical keystone, from the
    // heartbeat's values): measured 0.043 against 0.070 block lengths at most, up to 3.2 above the surface.
    const double a = rig.heartbeat_value("scale").value_or(0), g = rig.heartbeat_value("keystone").value_or(0);
    const double b = rig.heartbeat_value("shear").value_or(0), h = rig.heartbeat_value("vertical_keystone").value_or(0);
    REQUIRE(a > 0);
    const cv::Matx33d full(a, b, 0, 0, a, 0, g, h, 1), along(a, 0, 0, 0, a, 0, g, 0, 1);
    const cv::Matx33d only_along = along * full.inv() * board::camera_to_board_h(after);
    calibration_t along_only = after;
    for (int i = 0; i < 9; ++i) along_only.camera_to_board[i] = only_along(i / 3, i % 3);
    double worst_up = 0, worst_up_along = 0;
    for (double y : {1.2, 2.2, 3.2}) {
      for (double x : {-4.0, -2.0, 0.0, 2.0, 4.0}) {
        worst_up = std::max(worst_up, std::abs(calibrated_x(after, camera, x, y) - x));
        worst_up_along = std::max(worst_up_along, std::abs(calibrated_x(along_only, camera, x, y) - x));
      }
    }
    INFO("board x up to 3.2 block lengths above the surface: worst " << worst_up << ", with the correction along the board only "
                                                                     << worst_up_along);
    CHECK(worst_up < 0.05);
    CHECK(worst_up < 0.75 * worst_up_along);
    CHECK(log.find("end lines lean") != std::string::npos);
    // A block from the edge to 1 read this long before: the heartbeat reports it.
    const double read = calibrated_x(before, camera, 1.0) - calibrated_x(before, camera, 0.0);
    CHECK(rig.heartbeat_value("block_length").value_or(0) == Approx(read).epsilon(0.005));
    for (int i = 0; i < 9; ++i) CHECK(after.camera_to_projector[i] == before.camera_to_projector[i]);
  }
  {
    // Measured again: a correction below --scale-min-change, the file is left as it is.
    const calibration_t corrected = board::load_calibration(output);
    FakeRig rig(camera, projector);
    rig.set_scene(blocks);
    const Child child = spawn({program(), "--lcm-url", kUrl, "--output", output, "--scale-from-blocks", "--scale-blocks", "4"},
                              temp("again.err"));
    const ReapOnExit reap_child{child};
    const int code = rig.run_until_exit(child);
    const std::string log = slurp(child.stderr_path);
    INFO(log);
    CHECK(code == 0);
    CHECK(log.find("left as it is") != std::string::npos);
    CHECK(board::load_calibration(output).utime == corrected.utime);
  }
  {
    // Told that six blocks stand where four do: every frame counts four, so nothing is measured.
    const calibration_t corrected = board::load_calibration(output);
    FakeRig rig(camera, projector);
    rig.set_scene(blocks);
    const Child child = spawn({program(), "--lcm-url", kUrl, "--output", output, "--scale-from-blocks", "--scale-frames", "4",
                               "--scale-blocks", "6"},
                              temp("six.err"));
    const ReapOnExit reap_child{child};
    const int code = rig.run_until_exit(child);
    const std::string log = slurp(child.stderr_path);
    INFO(log);
    CHECK(code == 1);
    CHECK(log.find("blocks counted per frame: 4 in 4 frames") != std::string::npos);
    CHECK(log.find("count 6 (--scale-blocks)") != std::string::npos);
    CHECK(board::load_calibration(output).utime == corrected.utime);
  }
  {
    // An empty board: nothing to measure, a message saying what to do, the file untouched.
    const calibration_t corrected = board::load_calibration(output);
    FakeRig rig(camera, projector);
    const Child child = spawn({program(), "--lcm-url", kUrl, "--output", output, "--scale-from-blocks", "--scale-frames", "4"},
                              temp("empty.err"));
    const ReapOnExit reap_child{child};
    const int code = rig.run_until_exit(child);
    const std::string log = slurp(child.stderr_path);
    INFO(log);
    CHECK(code == 1);
    CHECK(log.find("stand 3 or more blocks on the bottom row") != std::string::npos);
    CHECK(board::load_calibration(output).utime == corrected.utime);
  }
  {
    // --serve serves a rewritten file (e.g. after --scale-from-blocks in another process) without a restart.
    FakeRig rig(camera, projector);
    const Child child = spawn({program(), "--lcm-url", kUrl, "--output", output, "--serve", "--republish", "0.3"},
                              temp("reload.err"));
    const ReapOnExit reap_child{child};
    REQUIRE(rig.run_until([&] { return rig.published.has_value(); }, 10));
    calibration_t rewritten = board::load_calibration(output);
    rewritten.utime += 1000;
    board::save_calibration(output, rewritten);
    const bool served = rig.run_until([&] { return rig.published->utime == rewritten.utime; }, 5);
    const int status = stop_child(child);
    const std::string log = slurp(child.stderr_path);
    INFO(log);
    CHECK(served);
    CHECK(log.find("it changed") != std::string::npos);
  }
  std::remove(output.c_str());
}

TEST_CASE("bricklayer-calibrate --serve waits for a calibration file that is not there yet, then serves it") {
  // The exhibit's launcher starts --serve before anyone has calibrated: it must neither exit nor publish.
  const sim::CameraSetup camera;
  const sim::ProjectorSetup projector;
  const std::string output = temp("later.json");
  std::remove(output.c_str());
  FakeRig rig(camera, projector);
  const Child child = spawn({program(), "--lcm-url", kUrl, "--output", output, "--serve", "--republish", "0.3"},
                            temp("later.err"));
  const ReapOnExit reap_child{child};
  rig.run_until([] { return false; }, 1.5);
  int status = 0;
  CHECK(waitpid(child.pid, &status, WNOHANG) == 0);  // still running
  CHECK_FALSE(rig.published.has_value());
  REQUIRE(rig.last_heartbeat.has_value());
  CHECK(rig.last_heartbeat->status.find("no calibration yet") != std::string::npos);
  rig.send_self_check();  // nothing to check: ignored, not a crash
  rig.run_until([] { return false; }, 0.5);
  CHECK(rig.patterns_shown == 0);

  calibration_t written = board::default_calibration();
  written.utime = 4242;
  board::save_calibration(output, written);
  const bool served = rig.run_until([&] { return rig.published.has_value(); }, 5);
  status = stop_child(child);
  const std::string log = slurp(child.stderr_path);
  INFO(log);
  REQUIRE(served);
  CHECK(rig.published->utime == 4242);
  CHECK(log.find("SELF_CHECK ignored: no calibration") != std::string::npos);
  CHECK(WIFEXITED(status));
  CHECK(WEXITSTATUS(status) == 0);
  std::remove(output.c_str());
}

TEST_CASE("bricklayer-calibrate --serve waits out a bus that cannot be opened, then serves once the route is back") {
  // No multicast route yet (the exhibit's machine booting, a switch power-cycled): the process must not
  // exit (the launcher would restart it in a loop) but wait, and serve once the bus can be opened.
  const std::string output = temp("noroute.json");
  calibration_t written = board::default_calibration();
  written.utime = 777;
  board::save_calibration(output, written);
  REQUIRE(std::system("ip route del 224.0.0.0/4 dev lo") == 0);
  const Child child = spawn({program(), "--lcm-url", kUrl, "--output", output, "--serve", "--republish", "0.3"},
                            temp("noroute.err"));
  const ReapOnExit reap_child{child};
  usleep(1500 * 1000);  // a few bus reopen attempts (once a second)
  int status = 0;
  const bool running = waitpid(child.pid, &status, WNOHANG) == 0;
  REQUIRE(std::system("ip route add 224.0.0.0/4 dev lo") == 0);
  CHECK(running);
  FakeRig rig(sim::CameraSetup{}, sim::ProjectorSetup{});
  const bool served = rig.run_until([&] { return rig.published.has_value(); }, 10);
  status = stop_child(child);
  const std::string log = slurp(child.stderr_path);
  INFO(log);
  CHECK(log.find("cannot open the LCM bus") != std::string::npos);
  REQUIRE(served);
  CHECK(rig.published->utime == 777);
  CHECK(WIFEXITED(status));
  CHECK(WEXITSTATUS(status) == 0);
  std::remove(output.c_str());
}

TEST_CASE("bricklayer-calibrate fails clearly when the projector does not answer") {
  const sim::CameraSetup camera;
  const sim::ProjectorSetup projector;
  FakeRig rig(camera, projector, /*answer_projector=*/false);
  const std::string output = temp("never.json");
  const Child child = spawn({program(), "--lcm-url", kUrl, "--output", output, "--timeout", "0.3"}, temp("noprojector.err"));
  const ReapOnExit reap_child{child};
  const int code = rig.run_until_exit(child);
  const std::string log = slurp(child.stderr_path);
  INFO(log);
  CHECK(code == 1);
  CHECK(log.find("is bricklayer-projection running?") != std::string::npos);
  CHECK_FALSE(std::ifstream(output).good());
}

TEST_CASE("bricklayer-calibrate refuses bad flags and a bad calibration file") {
  const std::string bad = temp("bad.json");
  std::ofstream(bad) << "{\"format\": \"bricklayer-calibration\", \"version\": 1}";
  struct Case {
    std::vector<std::string> args;
    int code;
    const char* expect;
  };
  const std::vector<Case> cases = {
      {{"--projector-size", "huge"}, 2, "--projector-size"},
      {{"--max-error-px", "-1"}, 2, "--max-error-px must be > 0"},
      {{"--self-check", "--output", bad}, 1, "missing key"},
      {{"--self-check", "--output", temp("absent.json")}, 1, "cannot open"},
      {{"--board", temp("absent-board.json")}, 1, "absent-board.json"},
      {{"--scale-from-blocks", "--serve"}, 2, "exclude each other"},
      {{"--scale-from-blocks", "--scale-frames", "0"}, 2, "--scale-frames must be"},
      {{"--scale-from-blocks", "--scale-blocks", "-1"}, 2, "--scale-blocks must be"},
      {{"--scale-from-blocks", "--output", temp("absent.json")}, 1, "cannot open"},
  };
  for (const Case& c : cases) {
    std::vector<std::string> args = {program(), "--lcm-url", kUrl};
    args.insert(args.end(), c.args.begin(), c.args.end());
    const Child child = spawn(args, temp("flags.err"));
    const ReapOnExit reap_child{child};
    const int status = wait_child(child, 30, "after starting");
    const std::string log = slurp(child.stderr_path);
    INFO(c.args[0] << ": " << log);
    CHECK(WIFEXITED(status));
    CHECK(WEXITSTATUS(status) == c.code);
    CHECK(log.find(c.expect) != std::string::npos);
  }
  std::remove(bad.c_str());

  const std::string written = temp("default.json");
  const Child child = spawn({program(), "--write-default", "--output", written}, temp("default.err"));
  const ReapOnExit reap_child{child};
  const int status = wait_child(child, 30, "after starting");
  CHECK(WEXITSTATUS(status) == 0);
  const calibration_t d = board::load_calibration(written);
  CHECK(d.projector_width == 1024);
  std::remove(written.c_str());
}

#ifdef BRICKLAYER_HAVE_PROJECTION
TEST_CASE("bricklayer-calibrate with the real bricklayer-projection (headless) and a closed-loop camera") {
  const uint64_t seed = 9;
  const sim::CameraSetup camera = sim::CameraSetup::random(seed);
  const sim::ProjectorSetup projector = sim::ProjectorSetup::random(seed);
  const std::string output = temp("with-projection.json");
  std::remove(output.c_str());
  FakeRig rig(camera, projector, /*answer_projector=*/false, /*follow_projector=*/true);
  ::setenv("SDL_AUDIODRIVER", "dummy", 1);
  const Child projection = spawn({std::string(BRICKLAYER_BINARY_DIR) + "/bin/bricklayer-projection", "--lcm-url", kUrl,
                                  "--headless", "--mute"},
                                 temp("projection.err"));
  const ReapOnExit reap_projection{projection};
  const Child child = spawn({program(), "--lcm-url", kUrl, "--output", output, "--timeout", "2"}, temp("calibrate.err"));
  const ReapOnExit reap_child{child};
  const int code = rig.run_until_exit(child, 60);
  int status = stop_child(projection);
  INFO("calibrate:\n" << slurp(child.stderr_path) << "projection:\n" << slurp(projection.stderr_path));
  REQUIRE(code == 0);
  {
    // A wrong --projector-size is caught from the size of the pattern the projector reports.
    FakeRig again(camera, projector, false, true);
    const Child projection2 = spawn({std::string(BRICKLAYER_BINARY_DIR) + "/bin/bricklayer-projection", "--lcm-url", kUrl,
                                     "--headless", "--mute"},
                                    temp("projection2.err"));
    const ReapOnExit reap_projection2{projection2};
    const Child wrong = spawn({program(), "--lcm-url", kUrl, "--output", temp("wrong.json"), "--projector-size", "800x600", "--timeout", "2"},
                              temp("wrong.err"));
    const ReapOnExit reap_wrong{wrong};
    const int wrong_code = again.run_until_exit(wrong, 30);
    status = stop_child(projection2);
    const std::string log = slurp(wrong.stderr_path);
    INFO(log);
    CHECK(wrong_code == 1);
    CHECK(log.find("but --projector-size is 800x600") != std::string::npos);
  }
  CHECK(rig.patterns_shown >= 6);
  const calibration_t saved = board::load_calibration(output);
  const double worst = max_mapping_error(saved, camera, projector);
  INFO("max mapping error " << worst);
  CHECK(worst < 1.5);
  std::remove(output.c_str());
}
#endif
