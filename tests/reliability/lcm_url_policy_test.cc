// Every process: the default LCM URL stays on this host (ttl=0), and a URL that would route the bus
// beyond the local network (ttl > 1, also when hidden behind an earlier ttl=0 option) or names an
// unknown provider is refused at start with a clear error and a non-zero exit -- before the process
// opens the bus. Runs each real binary.
#include <catch2/catch.hpp>

#include <unistd.h>

#include <filesystem>

#include "bricklayer/common/lcm_url.h"
#include "bricklayer/launcher/process.h"
#include "reliability_test_util.h"

using namespace bricklayer;
using namespace std::chrono_literals;
namespace fs = std::filesystem;

namespace {

const std::vector<std::vector<std::string>> kBinaries = {
    {"bricklayer-prediction"},
    {"bricklayer-vision"},
    {"bricklayer-projection", "--headless"},
    {"bricklayer-planner"},
    {"bricklayer-calibrate", "--serve"},
};

struct Outcome {
  launcher::ExitStatus status;
  std::string output;
};

Outcome run(std::vector<std::string> argv, const std::vector<std::string>& env = {}) {
  argv[0] = test::bin(argv[0]);
  launcher::SpawnOptions o;
  o.env = env;
  o.env.push_back("SDL_VIDEODRIVER=offscreen");
  o.env.push_back("SDL_AUDIODRIVER=dummy");
  o.stdout_path = fs::temp_directory_path() / ("bricklayer-url-" + std::to_string(::getpid()) + ".log");
  o.merge_stderr = true;
  auto p = launcher::Process::spawn(argv, o);
  auto st = p.wait_for(10s);
  if (!st) st = p.stop(2s);
  return {*st, test::slurp(o.stdout_path)};
}

}  // namespace

TEST_CASE("the default LCM URL is host-only (ttl=0)") {
  ::unsetenv("LCM_DEFAULT_URL");
  CHECK(resolve_lcm_url("") == kDefaultLcmUrl);
  CHECK(std::string(kDefaultLcmUrl).find("ttl=0") != std::string::npos);
  CHECK_NOTHROW(check_lcm_url(kDefaultLcmUrl));
  CHECK_NOTHROW(check_lcm_url("udpm://239.255.76.67:7667?ttl=1"));
  CHECK_THROWS_AS(check_lcm_url("udpm://239.255.76.67:7667?ttl=2"), std::invalid_argument);
  // LCM keeps the last value of a repeated option: ttl=0 first must not hide ttl=5 after it.
  CHECK_THROWS_AS(check_lcm_url("udpm://239.255.76.67:7667?ttl=0&ttl=5"), std::invalid_argument);
  CHECK_THROWS_AS(check_lcm_url("udpm://239.255.76.67:7667?recv_buf_size=100000&ttl=255"), std::invalid_argument);
  CHECK_THROWS_AS(check_lcm_url("http://example.org"), std::invalid_argument);
}

TEST_CASE("every process refuses a routed URL (ttl > 1) with a clear error and a non-zero exit") {
  for (const auto& base : kBinaries) {
    for (const std::string url : {"udpm://239.255.76.67:7667?ttl=2", "udpm://239.255.76.67:7667?ttl=0&ttl=32",
                                  "bogus://nowhere"}) {
      INFO(base[0] << " --lcm-url " << url);
      auto argv = base;
      argv.push_back("--lcm-url=" + url);
      const Outcome flag = run(argv);
      INFO(flag.output);
      CHECK(!flag.status.clean());
      CHECK(flag.status.signal == 0);  // an error exit, not a crash
      CHECK((flag.output.find("ttl") != std::string::npos || flag.output.find("provider") != std::string::npos));
      // The same URL from the environment is refused the same way.
      const Outcome env = run(base, {"LCM_DEFAULT_URL=" + url});
      INFO(env.output);
      CHECK(!env.status.clean());
      CHECK(env.status.signal == 0);
    }
  }
}
