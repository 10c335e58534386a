// Records the demo log the inspect tests read (a CTest fixture, run once inside its own network
// namespace): the real launcher with the real logger, simcam, vision, prediction and projection
// playing a 7-second scenario built for the report: a pile that turns red and falls, one that turns
// red and is fixed, two rounds (START_ROUND over the bus, 2-second rounds), three malformed stacks
// (counted as errors), the prediction process killed once (restarted by the launcher), and the study
// messages of three finished sessions and an aborted one, as the study session driver publishes them
// (the driver itself is not written yet; the report's study tables come from these messages).
// Usage: inspect_record_demo_log OUT_DIR   (writes OUT_DIR/demo.lcmlog; exit 0 when it holds all of it)
#include <lcm/lcm-cpp.hpp>
#include <signal.h>

#include <array>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <thread>

#include "bricklayer/command_t.hpp"
#include "bricklayer/heartbeat_t.hpp"
#include "bricklayer/image_t.hpp"
#include "bricklayer/launcher/process.h"
#include "bricklayer/study_answer_t.hpp"
#include "bricklayer/study_session_t.hpp"
#include "bricklayer/study_trial_t.hpp"

using namespace bricklayer;
using namespace std::chrono_literals;
namespace fs = std::filesystem;

namespace {

constexpr const char* kUrl = "udpm://239.255.76.67:7667?ttl=0";

// Holds (keyframes are steps): block 2 rests on block 1 until it is pushed past block 1's end.
constexpr const char* kScenario = R"({
  "description": "inspect test: a pile that turns red and falls, one that turns red and is fixed",
  "nuisance": "mild", "seed": 4, "duration_s": 7,
  "keyframes": [
    {"t": 0.0, "blocks": []},
    {"t": 0.4, "blocks": [{"id": 1, "row": 0, "x": -0.6}, {"id": 2, "row": 1, "x": -0.9}]},
    {"t": 1.4, "blocks": [{"id": 1, "row": 0, "x": -0.6}, {"id": 2, "row": 1, "x": -0.05}]},
    {"t": 2.4, "blocks": [{"id": 1, "row": 0, "x": -0.6}]},
    {"t": 3.4, "blocks": [{"id": 1, "row": 0, "x": -0.5}, {"id": 2, "row": 1, "x": -0.9}]},
    {"t": 4.4, "blocks": [{"id": 1, "row": 0, "x": -0.5}, {"id": 2, "row": 1, "x": 0.05}]},
    {"t": 5.2, "blocks": [{"id": 1, "row": 0, "x": -0.5}, {"id": 2, "row": 1, "x": -0.9}]}
  ]})";

constexpr double kFps = 20;

struct Watch {
  std::map<std::string, heartbeat_t> last;
  int64_t frame = -1;  // the newest camera frame: scenario time = frame / fps
  void beat(const lcm::ReceiveBuffer*, const std::string&, const heartbeat_t* hb) { last[hb->module] = *hb; }
  void image(const lcm::ReceiveBuffer*, const std::string&, const image_t* im) { frame = std::max(frame, im->frame_number); }
  double scenario_s() const { return static_cast<double>(frame) / kFps; }
};

void command(lcm::LCM& bus, int32_t what) {
  command_t c{};
  c.command = what;
  c.sequence = what;
  bus.publish("BL_COMMAND", &c);
}

// One study session's results: its state (done or aborted), both trials, the three answers.
void study_session(lcm::LCM& bus, const std::string& id, const std::string& subject, int8_t condition, bool aborted,
                   int32_t trial1, int32_t trial2, const std::array<int8_t, 3>& outcomes) {
  int64_t utime = 1796000000000000;
  for (int8_t trial = 1; trial <= 2; ++trial) {
    study_trial_t t{};
    t.utime = ++utime;
    t.session_id = id;
    t.subject_id = subject;
    t.condition = condition;
    t.trial = trial;
    t.attempt = 1;
    t.duration_ms = 120000;
    t.score = trial == 1 ? trial1 : trial2;
    t.num_blocks = 4;
    bus.publish("BL_STUDY_TRIAL", &t);
  }
  for (int8_t problem = 1; problem <= 3; ++problem) {
    study_answer_t a{};
    a.utime = ++utime;
    a.session_id = id;
    a.subject_id = subject;
    a.condition = condition;
    a.problem = problem;
    a.name = "problem-" + std::to_string(problem);
    a.attempt = 1;
    a.outcome = outcomes[static_cast<size_t>(problem - 1)];
    a.stands = a.outcome != study_answer_t::OUTCOME_FAILED;
    a.minimum_added = problem == 3 ? -1 : 1;
    a.reason = "recorded by the inspect test";
    bus.publish("BL_STUDY_ANSWER", &a);
  }
  study_session_t s{};
  s.utime = ++utime;
  s.session_id = id;
  s.subject_id = subject;
  s.condition = condition;
  s.step = aborted ? study_session_t::STEP_PROBLEM_2 : study_session_t::STEP_DONE;
  s.state = aborted ? study_session_t::STATE_ABORTED : study_session_t::STATE_FINISHED;
  s.attempt = 1;
  s.instruction = "thank you";
  bus.publish("BL_STUDY_SESSION", &s);
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) {
    std::cerr << "usage: inspect_record_demo_log OUT_DIR\n";
    return 2;
  }
  const fs::path out = fs::absolute(argv[1]);
  fs::remove_all(out);
  fs::create_directories(out);
  std::ofstream(out / "scenario.json") << kScenario;
  const std::string bin = std::string(BRICKLAYER_BINARY_DIR) + "/bin";
  std::ofstream(out / "profile.json") << R"({
  "description": "inspect test demo", "stop_timeout_s": 5,
  "logger": {"file": ")" << (out / "demo").string() << R"("},
  "modules": [
    {"name": "prediction", "command": ["bricklayer-prediction"], "restart": "always"},
    {"name": "projection", "command": ["bricklayer-projection", "--headless", "--round-seconds", "2"], "restart": "always"},
    {"name": "vision", "command": ["bricklayer-vision"], "restart": "always"},
    {"name": "simcam", "command": ["bricklayer-simcam", "--scenario", ")" << (out / "scenario.json").string() << R"(", "--fps", "20", "--loop"], "restart": "always"}
  ]})";

  lcm::LCM bus(kUrl);
  if (!bus.good()) return 1;
  Watch watch;
  bus.subscribe("BL_HEARTBEAT", &Watch::beat, &watch);
  bus.subscribe("BL_IMAGE", &Watch::image, &watch);

  launcher::SpawnOptions options;
  options.env = {"SDL_VIDEODRIVER=offscreen", "SDL_AUDIODRIVER=dummy"};
  options.stdout_path = (out / "launch.out").string();
  options.merge_stderr = true;
  // --duration is only a safety net: the recording is stopped by scenario time (frames), so a busy
  // machine that renders slowly still records the whole scenario.
  launcher::Process launch = launcher::Process::spawn(
      {bin + "/bricklayer-launch", "--bin-dir", bin, "--root", BRICKLAYER_SOURCE_DIR, "--lcm-url", kUrl,
       (out / "profile.json").string(), "--duration", "60"},
      options);

  // Pumps the bus until the scenario reaches `t` seconds (false after 40 s of wall time).
  auto until_scenario = [&](double t) {
    auto give_up = std::chrono::steady_clock::now() + 40s;
    while (watch.scenario_s() < t && std::chrono::steady_clock::now() < give_up) bus.handleTimeout(10);
    return watch.scenario_s() >= t;
  };
  if (!until_scenario(0.2)) {
    std::cerr << "record: no camera frames (see " << (out / "launch.out").string() << ")\n";
    return 1;
  }
  command(bus, command_t::START_ROUND);  // round 1 (2 s of wall time)
  until_scenario(0.8);
  for (int i = 0; i < 3; ++i) {  // bytes that are no stack_t: prediction and projection count errors
    std::string junk = "not a stack " + std::to_string(i) + " of the inspect test";
    bus.publish("BL_STACK", junk.data(), static_cast<unsigned>(junk.size()));
  }
  const int8_t C = study_answer_t::OUTCOME_CORRECT, X = study_answer_t::OUTCOME_EXCESS, F = study_answer_t::OUTCOME_FAILED;
  study_session(bus, "s01", "p01", study_session_t::CONDITION_BLUE, false, 40, 60, {C, X, F});
  study_session(bus, "s02", "p02", study_session_t::CONDITION_PROPOSED, false, 50, 100, {X, C, C});
  study_session(bus, "s03", "p03", study_session_t::CONDITION_PROPOSED, false, 80, 120, {C, C, F});
  study_session(bus, "s04", "p04", study_session_t::CONDITION_BLUE, false, 30, 90, {F, X, C});
  study_session(bus, "s05", "p05", study_session_t::CONDITION_RED, true, 70, 10, {C, C, C});  // aborted: left out
  until_scenario(2.8);
  if (!watch.last.count("prediction")) {
    std::cerr << "record: no heartbeat from prediction\n";
    return 1;
  }
  const int32_t old_pid = watch.last.at("prediction").pid;
  ::kill(old_pid, SIGKILL);  // between the two piles; the launcher restarts it
  until_scenario(3.0);
  command(bus, command_t::RESET_ROUND);
  command(bus, command_t::START_ROUND);  // round 2
  bool whole = until_scenario(6.8);
  auto settle = std::chrono::steady_clock::now() + 1s;  // the last predictions and heartbeats
  while (std::chrono::steady_clock::now() < settle) bus.handleTimeout(10);
  launch.signal(SIGTERM);
  auto status = launch.wait_for(20s);
  if (!status) {
    std::cerr << "record: the launcher did not stop on SIGTERM\n";
    return 1;
  }
  if (!whole) {
    std::cerr << "record: the scenario did not reach 6.8 s within 40 s\n";
    return 1;
  }
  if (watch.last.at("prediction").pid == old_pid) {
    std::cerr << "record: prediction was not restarted\n";
    return 1;
  }
  fs::path log = out / "demo.0";
  if (!fs::exists(log)) {
    std::cerr << "record: no log at " << log << "\n";
    return 1;
  }
  fs::rename(log, out / "demo.lcmlog");
  std::cout << "record: " << (out / "demo.lcmlog").string() << " (" << fs::file_size(out / "demo.lcmlog") << " bytes), launcher "
            << status->describe() << "\n";
  return 0;
}
