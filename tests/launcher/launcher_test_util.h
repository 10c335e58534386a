// What the launcher's process tests share: a scratch root and bricklayer-launch started on a profile in it.
#pragma once

#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "bricklayer/launcher/process.h"
#include "harness/live_bus.h"
#include "harness/scratch.h"

namespace bricklayer::test {

struct TempDir {
  std::filesystem::path path;
  explicit TempDir(const std::string& tag) {
    path = std::filesystem::temp_directory_path() / ("bricklayer-launcher-" + tag + "-" + std::to_string(::getpid()));
    std::filesystem::remove_all(path);
    std::filesystem::create_directories(path);
  }
  ~TempDir() {
    std::error_code ec;
    std::filesystem::remove_all(path, ec);
  }
  std::filesystem::path write(const std::string& name, const std::string& text) const {
    std::ofstream(path / name) << text;
    return path / name;
  }
  std::string read(const std::string& name) const {
    std::ifstream in(path / name);
    std::stringstream s;
    s << in.rdbuf();
    return s.str();
  }
};

// bricklayer-launch on profile with the build's binaries, the test bus, output in launch<tag>.out/.err.
inline launcher::Process launch(const TempDir& dir, const std::filesystem::path& profile, std::vector<std::string> extra = {},
                                const std::string& tag = "") {
  std::vector<std::string> argv = {harness::program_path("bricklayer-launch"), "--root", dir.path.string(), "--bin-dir",
                                   (harness::binary_dir() / "bin").string(), "--lcm-url", harness::kLiveUrl, profile.string()};
  argv.insert(argv.end(), extra.begin(), extra.end());
  launcher::SpawnOptions o;
  o.stdout_path = (dir.path / ("launch" + tag + ".out")).string();
  o.stderr_path = (dir.path / ("launch" + tag + ".err")).string();
  o.env = {"DISPLAY="};
  return launcher::Process::spawn(argv, o);
}

}  // namespace bricklayer::test
