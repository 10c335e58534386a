// Launch profiles: every shipped profile parses; mistakes are loud and say where.
#include "bricklayer/launcher/profile.h"

#include <catch2/catch.hpp>

#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "bricklayer/launcher/process.h"
#include "profile_error.h"

using namespace bricklayer::launcher;
using bricklayer::test::profile_error;

TEST_CASE("every profile in launch/profiles parses") {
  int n = 0;
  for (const auto& entry : std::filesystem::directory_iterator(std::string(BRICKLAYER_SOURCE_DIR) + "/launch/profiles")) {
    if (entry.path().extension() != ".json") continue;
    INFO(entry.path());
    Profile p = load_profile(entry.path().string());
    CHECK_FALSE(p.modules.empty());
    CHECK(p.name == entry.path().stem().string());
    ++n;
  }
  CHECK(n >= 4);
  Profile demo = load_profile(std::string(BRICKLAYER_SOURCE_DIR) + "/launch/profiles/demo.json");
  CHECK(demo.headless_duration_s == 30);
  REQUIRE(demo.logger);
  bool projection_has_both = false;
  for (const auto& m : demo.modules)
    if (m.name == "projection") projection_has_both = !m.command.empty() && !m.command_with_display.empty();
  CHECK(projection_has_both);
}

TEST_CASE("every shipped profile's programs exist, take the flags it gives them, and send the heartbeat it waits for") {
  for (const auto& entry : std::filesystem::directory_iterator(std::string(BRICKLAYER_SOURCE_DIR) + "/launch/profiles")) {
    if (entry.path().extension() != ".json") continue;
    const Profile p = load_profile(entry.path().string());
    for (const ModuleSpec& m : p.modules) {
      for (const auto* command : {&m.command, &m.command_with_display}) {
        if (command->empty()) continue;
        INFO(entry.path().filename().string() << ": module " << m.name << ": " << (*command)[0]);
        const std::string program = std::string(BRICKLAYER_BINARY_DIR) + "/bin/" + (*command)[0];
        REQUIRE(std::filesystem::exists(program));
        // Every process is named after its program (bricklayer-X sends heartbeats as X).
        CHECK("bricklayer-" + m.heartbeat == (*command)[0]);
        std::string help;
        FILE* out = popen((program + " --help 2>&1").c_str(), "r");
        REQUIRE(out);
        char buf[4096];
        while (fgets(buf, sizeof buf, out)) help += buf;
        pclose(out);
        for (const std::string& arg : *command) {
          if (arg.rfind("--", 0) != 0) continue;
          const std::string flag = arg.substr(0, arg.find('='));
          INFO(flag);
          CHECK((help.find("  " + flag + "=") != std::string::npos || help.find("  " + flag + " ") != std::string::npos));
        }
      }
    }
  }
}

TEST_CASE("a profile's defaults") {
  Profile p = parse_profile(R"({"modules":[{"name":"prediction","command":["bricklayer-prediction"]}]})", "t");
  REQUIRE(p.modules.size() == 1);
  CHECK(p.modules[0].heartbeat == "prediction");
  CHECK(p.modules[0].restart == RestartPolicy::kAlways);
  CHECK(p.modules[0].ready_timeout_s == 10);
  CHECK_FALSE(p.logger);
  CHECK(p.duration_s == 0);
  CHECK(p.stop_timeout_s == 5);
}

TEST_CASE("profile mistakes are loud and name the place") {
  CHECK(profile_error("{").find("not valid JSON") != std::string::npos);
  CHECK(profile_error(R"({"modules":[], "modulez":1})").find("unknown key 'modulez'") != std::string::npos);
  CHECK(profile_error(R"({"modules":[{"name":"a"}]})").find("'a': 'command' is required") != std::string::npos);
  CHECK(profile_error(R"({"modules":[{"name":"a","command":[]}]})").find("'command' is empty") != std::string::npos);
  CHECK(profile_error(R"({"modules":[{"name":"a","command":["x"],"restart":"sometimes"}]})")
            .find("'sometimes' is not one of always, on-failure, never") != std::string::npos);
  CHECK(profile_error(R"({"modules":[{"name":"a","command":["x"]},{"name":"a","command":["y"]}]})")
            .find("two modules are named 'a'") != std::string::npos);
  CHECK(profile_error(R"({"modules":[{"name":"a","command":["x"],"ready_timeout_s":-1}]})").find("ready_timeout_s") !=
        std::string::npos);
  CHECK(profile_error(R"({"modules":[{"name":"a","command":["x"],"env":["NOEQUALS"]}]})").find("NAME=value") !=
        std::string::npos);
  CHECK(profile_error(R"({"modules":[{"name":"a","command":["x"]}],"logger":{"rotat":3}})").find("unknown key 'rotat'") !=
        std::string::npos);
  CHECK(profile_error(R"({"modules":[]})").find("nothing to launch") != std::string::npos);
  CHECK_THROWS_AS(load_profile("/nonexistent/profile.json"), ProfileError);
}

TEST_CASE("bricklayer-launch --check prints the plan, or names every missing binary with its build target") {
  namespace fs = std::filesystem;
  const fs::path dir = fs::temp_directory_path() / ("bricklayer-launch-check-" + std::to_string(::getpid()));
  fs::create_directories(dir);
  auto run = [&](const std::string& profile_json) {
    std::ofstream(dir / "p.json") << profile_json;
    SpawnOptions o;
    o.stdout_path = (dir / "out").string();
    o.merge_stderr = true;
    o.env = {"DISPLAY="};
    auto p = Process::spawn({std::string(BRICKLAYER_BINARY_DIR) + "/bin/bricklayer-launch", "--check", "--root",
                             dir.string(), (dir / "p.json").string()},
                            o);
    auto st = p.wait_for(std::chrono::seconds(10));
    REQUIRE(st);
    std::ifstream in(dir / "out");
    std::stringstream text;
    text << in.rdbuf();
    return std::make_pair(st->code, text.str());
  };
  auto [ok_code, ok_out] = run(R"({"headless_duration_s":7,"logger":{"file":"logs/x"},"modules":[
      {"name":"a","command":["/bin/sleep","1"],"heartbeat":""}]})");
  INFO(ok_out);
  CHECK(ok_code == 0);
  // The logger is our own (modules/logger), up once its heartbeat arrives, with the profile's defaults
  // (rotate 10, split 100 MB) and the file under the root.
  CHECK(ok_out.find("logger (heartbeat logger, restart always): " + std::string(BRICKLAYER_BINARY_DIR) +
                    "/bin/bricklayer-logger --lcm-url=") != std::string::npos);
  CHECK(ok_out.find(" --rotate=10 --split-mb=100 " + (dir / "logs" / "x").string() + "\n") != std::string::npos);
  CHECK(ok_out.find("a (no heartbeat, restart always): /bin/sleep 1") != std::string::npos);
  CHECK(ok_out.find("duration: 7 s") != std::string::npos);
  CHECK_FALSE(fs::exists(dir / "logs"));  // a check creates nothing

  auto [bad_code, bad_out] = run(R"({"modules":[{"name":"v","command":["bricklayer-nope"]},
      {"name":"w","command":["tools/missing.sh"]}]})");
  INFO(bad_out);
  CHECK(bad_code == 2);
  CHECK(bad_out.find("module 'v' needs 'bricklayer-nope'") != std::string::npos);
  CHECK(bad_out.find("--target bricklayer-nope") != std::string::npos);
  CHECK(bad_out.find("module 'w' needs 'tools/missing.sh'") != std::string::npos);
  fs::remove_all(dir);
}

TEST_CASE("bricklayer-launch --check checks every file the modules will read") {
  namespace fs = std::filesystem;
  const fs::path dir = fs::temp_directory_path() / ("bricklayer-launch-files-" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir / "launch" / "scenarios");
  std::ofstream(dir / "launch" / "scenarios" / "here.json") << "{}";
  auto run = [&](const std::string& profile_json) {
    std::ofstream(dir / "p.json") << profile_json;
    SpawnOptions o;
    o.stdout_path = (dir / "out").string();
    o.merge_stderr = true;
    o.env = {"DISPLAY="};
    auto p = Process::spawn({std::string(BRICKLAYER_BINARY_DIR) + "/bin/bricklayer-launch", "--check", "--root",
                             dir.string(), "--bin-dir", std::string(BRICKLAYER_BINARY_DIR) + "/bin", (dir / "p.json").string()},
                            o);
    auto st = p.wait_for(std::chrono::seconds(60));
    REQUIRE(st);
    std::ifstream in(dir / "out");
    std::stringstream text;
    text << in.rdbuf();
    return std::make_pair(st->code, text.str());
  };
  // Everything there: a runtime node checks itself (--check-config), a program without that its
  // input-file flags (/bin/echo stands for one), the profile's needs.
  auto [ok_code, ok_out] = run(R"({"modules":[
      {"name":"prediction","command":["bricklayer-prediction"]},
      {"name":"sim","command":["/bin/echo","--scenario","launch/scenarios/here.json"],"heartbeat":"",
       "needs":["launch/scenarios/here.json"]},
      {"name":"camera","command":["bricklayer-camera","--device","0"]}]})");
  INFO(ok_out);
  CHECK(ok_code == 0);
  CHECK(ok_out.find("prediction: flags and files checked by bricklayer-prediction --check-config") != std::string::npos);
  CHECK(ok_out.find("sim: 1 input file of its command line checked (echo has no --check-config)") != std::string::npos);
  CHECK(ok_out.find("camera: flags and files checked by bricklayer-camera --check-config") != std::string::npos);

  // Each missing file is named with its module; the check fails.
  auto [bad_code, bad_out] = run(R"({"modules":[
      {"name":"sim","command":["/bin/echo","--scenario","launch/scenarios/gone.json","--font=fonts/none.ttf"],"heartbeat":""},
      {"name":"projection","command":["/bin/echo"],"heartbeat":"","needs":["calibration.json"]},
      {"name":"camera","command":["bricklayer-camera","--images","frames-gone"]}]})");
  INFO(bad_out);
  CHECK(bad_code == 2);
  CHECK(bad_out.find("module 'sim': --scenario launch/scenarios/gone.json: no such file") != std::string::npos);
  CHECK(bad_out.find("module 'sim': --font fonts/none.ttf: no such file") != std::string::npos);
  CHECK(bad_out.find("module 'projection' needs 'calibration.json' (the profile's needs), which does not exist") !=
        std::string::npos);
  CHECK(bad_out.find("module 'camera': its own check failed (exit code 2)") != std::string::npos);
  CHECK(bad_out.find("folder frames-gone: no such file or folder") != std::string::npos);
  fs::remove_all(dir);
}

TEST_CASE("the demo profile with its scenario file missing fails --check, naming the module and the file") {
  namespace fs = std::filesystem;
  const fs::path dir = fs::temp_directory_path() / ("bricklayer-launch-demo-check-" + std::to_string(::getpid()));
  fs::create_directories(dir);
  std::ifstream in(std::string(BRICKLAYER_SOURCE_DIR) + "/launch/profiles/demo.json");
  std::stringstream text;
  text << in.rdbuf();
  std::string demo = text.str();
  const std::string scenario = "build-4-optimum.json";
  REQUIRE(demo.find(scenario) != std::string::npos);
  demo.replace(demo.find(scenario), scenario.size(), "not-there.json");
  std::ofstream(dir / "demo.json") << demo;
  SpawnOptions o;
  o.stdout_path = (dir / "out").string();
  o.merge_stderr = true;
  o.env = {"DISPLAY="};
  auto p = Process::spawn({std::string(BRICKLAYER_BINARY_DIR) + "/bin/bricklayer-launch", "--check", "--root",
                           BRICKLAYER_SOURCE_DIR, "--bin-dir", std::string(BRICKLAYER_BINARY_DIR) + "/bin",
                           (dir / "demo.json").string()},
                          o);
  auto st = p.wait_for(std::chrono::seconds(60));
  REQUIRE(st);
  std::ifstream out_file(dir / "out");
  std::stringstream out;
  out << out_file.rdbuf();
  INFO(out.str());
  CHECK(st->code == 2);
  CHECK(out.str().find("module 'simcam'") != std::string::npos);
  CHECK(out.str().find("launch/scenarios/not-there.json") != std::string::npos);
  fs::remove_all(dir);
}

TEST_CASE("every shipped profile passes --check in the source tree") {
  for (const auto& entry : std::filesystem::directory_iterator(std::string(BRICKLAYER_SOURCE_DIR) + "/launch/profiles")) {
    if (entry.path().extension() != ".json") continue;
    SpawnOptions o;
    const std::string out = std::filesystem::temp_directory_path() / ("bricklayer-shipped-check-" + std::to_string(::getpid()));
    o.stdout_path = out;
    o.merge_stderr = true;
    o.env = {"DISPLAY="};
    auto p = Process::spawn({std::string(BRICKLAYER_BINARY_DIR) + "/bin/bricklayer-launch", "--check", "--root",
                             BRICKLAYER_SOURCE_DIR, "--bin-dir", std::string(BRICKLAYER_BINARY_DIR) + "/bin",
                             entry.path().string()},
                            o);
    auto st = p.wait_for(std::chrono::seconds(60));
    REQUIRE(st);
    std::ifstream in(out);
    std::stringstream text;
    text << in.rdbuf();
    INFO(entry.path().filename().string() << ":\n" << text.str());
    CHECK(st->code == 0);
    std::filesystem::remove(out);
  }
}

TEST_CASE("the logger spec: a disk budget, a frame policy, and the command line they become") {
  const Profile p = parse_profile(R"({"modules":[],"logger":{"file":"logs/exhibit-%Y%m%d","split_mb":100,
      "budget_mb":5000,"min_free_mb":1000,"frames":{"rate":2,"before_s":8}}})", "t");
  REQUIRE(p.logger);
  CHECK(p.logger->rotate == 0);  // a budget bounds the series: increment naming
  CHECK(p.logger->budget_mb == 5000);
  CHECK(p.logger->min_free_mb == 1000);
  REQUIRE(p.logger->frames);
  CHECK(p.logger->frames->rate == 2);
  CHECK(p.logger->frames->before_s == 8);
  CHECK(p.logger->frames->after_s == 10);  // the default
  CHECK(series_prefix("logs/exhibit-%Y%m%d") == "exhibit-");
  CHECK(series_prefix("logs/run") == "run.");
  const std::vector<std::string> args = logger_arguments(*p.logger, "/x/logs/exhibit-20261201");
  const std::vector<std::string> expected = {"--rotate=0", "--split-mb=100", "--series=exhibit-", "--budget-mb=5000",
                                             "--min-free-mb=1000", "--frame-rate=2", "--full-rate-before-s=8",
                                             "--full-rate-after-s=10", "/x/logs/exhibit-20261201"};
  CHECK(args == expected);
  // Without a budget or frames: as before (rotate 10, every frame).
  const Profile plain = parse_profile(R"({"modules":[],"logger":{"file":"logs/x"}})", "t");
  CHECK(logger_arguments(*plain.logger, "f") == std::vector<std::string>{"--rotate=10", "--split-mb=100", "f"});
  CHECK(profile_error(R"({"modules":[],"logger":{"budget_mb":100,"split_mb":60}})").find("bricklayer-logger would refuse it: --split-mb must be at most half of --budget-mb") !=
        std::string::npos);
  CHECK(profile_error(R"({"modules":[],"logger":{"frames":{"rate":2,"window":3}}})").find("unknown key 'window'") !=
        std::string::npos);
  CHECK(profile_error(R"({"modules":[],"logger":{"frames":{"rate":0}}})").find("'rate' must be >=") != std::string::npos);
  CHECK(profile_error(R"({"modules":[],"logger":{"frames":5}})").find("'frames' must be an object") != std::string::npos);
  // Ranges are the logger's own declaration, judged at load.
  CHECK(profile_error(R"({"modules":[],"logger":{"frames":{"rate":5000}}})").find("bricklayer-logger would refuse it: --frame-rate") !=
        std::string::npos);
  CHECK(profile_error(R"({"modules":[],"logger":{"frames":{"rate":2,"after_s":900}}})").find("--full-rate-after-s") !=
        std::string::npos);
  // Answers thinned with their frames: one more flag; only the two words.
  const Profile with = parse_profile(R"({"modules":[],"logger":{"file":"logs/x","frames":{"rate":2,"answers":"with_frames"}}})", "t");
  const std::vector<std::string> with_args = logger_arguments(*with.logger, "f");
  CHECK(std::count(with_args.begin(), with_args.end(), "--answers-with-frames") == 1);
  const Profile whole = parse_profile(R"({"modules":[],"logger":{"file":"logs/x","frames":{"rate":2,"answers":"whole"}}})", "t");
  const std::vector<std::string> whole_args = logger_arguments(*whole.logger, "f");
  CHECK(std::count(whole_args.begin(), whole_args.end(), "--answers-with-frames") == 0);
  CHECK(profile_error(R"({"modules":[],"logger":{"frames":{"rate":2,"answers":"some"}}})").find("'answers' must be") !=
        std::string::npos);
  // The windows' hourly allowance: one more flag when set.
  const Profile capped = parse_profile(R"({"modules":[],"logger":{"file":"logs/x","frames":{"rate":2,"max_mb_per_hour":450}}})", "t");
  const std::vector<std::string> capped_args = logger_arguments(*capped.logger, "f");
  CHECK(std::count(capped_args.begin(), capped_args.end(), "--max-mb-per-hour=450") == 1);
  CHECK(std::count(whole_args.begin(), whole_args.end(), "--max-mb-per-hour=450") == 0);
  CHECK(profile_error(R"({"modules":[],"logger":{"frames":{"rate":2,"max_mb_per_hour":-3}}})").find("'max_mb_per_hour' must be >=") !=
        std::string::npos);
  CHECK(profile_error(R"({"modules":[],"logger":{"frames":{"rate":2,"max_mb_per_hour":5000000}}})").find("--max-mb-per-hour") !=
        std::string::npos);
}

TEST_CASE("every shipped profile's logger command line is one bricklayer-logger accepts") {
  for (const auto& entry : std::filesystem::directory_iterator(std::string(BRICKLAYER_SOURCE_DIR) + "/launch/profiles")) {
    if (entry.path().extension() != ".json") continue;
    const Profile p = load_profile(entry.path().string());
    if (!p.logger) continue;
    std::string command = std::string(BRICKLAYER_BINARY_DIR) + "/bin/bricklayer-logger --check-config";
    for (const auto& a : logger_arguments(*p.logger, "/tmp/bricklayer-profile-check/x")) command += " '" + a + "'";
    INFO(entry.path().filename().string() << ": " << command);
    FILE* out = popen((command + " 2>&1").c_str(), "r");
    REQUIRE(out);
    std::string text;
    char buf[4096];
    while (fgets(buf, sizeof buf, out)) text += buf;
    INFO(text);
    CHECK(pclose(out) == 0);
  }
}
