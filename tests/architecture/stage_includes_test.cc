// The pipeline's stages stand on shared libraries, never on each other: no stage's library or program
// includes another stage's headers. What two stages share (the board and its calibration file, the
// detector, frames, patterns, messages, the runtime) lives below them, so a stage can be rebuilt,
// replaced or replayed alone. Benchmarks and tests may render frames with simcam: they are not stages.
#include <catch2/catch.hpp>

#include <filesystem>
#include <fstream>
#include <regex>
#include <set>
#include <string>

namespace fs = std::filesystem;

namespace {
const std::set<std::string> kStages = {"camera", "simcam", "vision", "prediction", "planner",
                                       "projection", "calibration", "logger"};

// Every "bricklayer/<stage>/..." include of another stage in the stage's src/ and include/.
std::vector<std::string> foreign_includes(const std::string& stage) {
  const fs::path root = fs::path(BRICKLAYER_SOURCE_DIR) / "modules" / stage;
  const std::regex include(R"re(^\s*#\s*include\s*"bricklayer/([a-z_]+)/)re");
  std::vector<std::string> out;
  for (const char* part : {"src", "include"}) {
    if (!fs::exists(root / part)) continue;
    for (const auto& e : fs::recursive_directory_iterator(root / part)) {
      if (!e.is_regular_file()) continue;
      std::ifstream in(e.path());
      std::string line;
      for (int n = 1; std::getline(in, line); ++n) {
        std::smatch m;
        if (std::regex_search(line, m, include) && m[1] != stage && kStages.count(m[1]))
          out.push_back(fs::relative(e.path(), BRICKLAYER_SOURCE_DIR).string() + ":" + std::to_string(n) + ": " + line);
      }
    }
  }
  return out;
}
}  // namespace

TEST_CASE("no stage includes another stage's headers") {
  for (const auto& stage : kStages) {
    INFO("modules/" << stage);
    REQUIRE(fs::exists(fs::path(BRICKLAYER_SOURCE_DIR) / "modules" / stage));
    const auto found = foreign_includes(stage);
    for (const auto& f : found) UNSCOPED_INFO(f);
    CHECK(found.empty());
  }
}

TEST_CASE("the include check sees an include of another stage") {
  // The check itself: a stage's own header path passes, another stage's is caught by the same pattern.
  const std::regex include(R"re(^\s*#\s*include\s*"bricklayer/([a-z_]+)/)re");
  std::smatch m;
  const std::string line = "#include \"bricklayer/calibration/calibrator.h\"";
  REQUIRE(std::regex_search(line, m, include));
  CHECK(m[1] == "calibration");
  CHECK(kStages.count(m[1]) == 1);
}
