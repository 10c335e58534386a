// bricklayer-study-session and bricklayer-study send as real processes on a real LCM bus (inside a
// private network namespace): the experimenter sends commands to a running session from
// another process (a pause before the first step runs does not apply; the abort does), and the driver exits
// by itself once the session is over.
#include <chrono>
#include <string>

#include <catch2/catch.hpp>

#include "bricklayer/common/channels.h"
#include "bricklayer/runtime/lcm_bus.h"
#include "bricklayer/study/channels.h"
#include "bricklayer/study_session_t.hpp"
#include "harness/program.h"
#include "harness/recorder.h"

using namespace bricklayer;
using S = bricklayer::study_session_t;
using namespace std::chrono_literals;

TEST_CASE("study session process: a pause that does not apply yet and an abort, sent by bricklayer-study send", "[process]") {
  const std::string url = "udpm://239.255.76.67:7667?ttl=0";
  runtime::LcmBus bus(url);
  auto rec = harness::Recorder::live(bus, {channel(study::kSessionChannel), channel(kHeartbeatChannel)});
  const std::string problems = std::string(BRICKLAYER_SOURCE_DIR) + "/launch/problems/";
  harness::Program session("bricklayer-study-session",
                           {"--subject", "p42", "--condition", "proposed", "--session-id", "live-p42",
                            "--clear-seconds", "0", "--problem-1", problems + "stabilise-two.json", "--problem-2",
                            problems + "stabilise-one.json", "--problem-3", problems + "score-100-four.json",
                            "--lcm-url", url});
  // Under the sanitizers its first heartbeat was seen to take more than 10 s: a bound for a hang, not a speed.
  REQUIRE(rec.wait_for_heartbeat("study-session", {}, 60s));
  const auto ready = rec.wait_for<S>(channel(study::kSessionChannel), [](const S& s) {
    return s.session_id == "live-p42" && s.step == S::STEP_TRIAL_1;
  });
  REQUIRE(ready);
  CHECK(ready->instruction == "Take every block off the board to begin the first game.");

  // No vision here: the step waits in READY, so pause does not apply; abort does.
  auto send = [&](const std::string& what) {
    const harness::Ran r = harness::run_program("bricklayer-study", {"send", what, "--session", "live-p42", "--lcm-url", url});
    INFO(r.err);
    CHECK(r.status.clean());
  };
  send("pause");
  rec.pump_for(300ms);
  CHECK(rec.all<S>(channel(study::kSessionChannel)).back().state == S::STATE_READY);
  send("abort");
  const auto aborted = rec.wait_for<S>(channel(study::kSessionChannel), [](const S& s) { return s.state == S::STATE_ABORTED; });
  REQUIRE(aborted);
  CHECK(aborted->instruction == "The session has ended. Thank you!");
  const auto status = session.wait_exit(10s);
  REQUIRE(status);
  CHECK(status->clean());
  // The heartbeat counted the command that did not apply as a warning, not an error.
  const auto hb = rec.last_heartbeat("study-session");
  REQUIRE(hb);
  CHECK(hb->errors == 0);
}
