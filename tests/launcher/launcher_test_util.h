// What the launcher's process tests share: a scratch root and bricklayer-launch started on a profile in it.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "bricklayer/launcher/process.h"
#include "harness/live_bus.h"
#include "harness/scratch.h"

namespace bricklayer::test {

// A scratch root (harness::ScratchDir: removed at the end unless BRICKLAYER_KEEP_SCRATCH=1) with the
// profile and output helpers the launcher tests use.
struct TempDir {
  harness::ScratchDir scratch;
  std::filesystem::path path;
  explicit TempDir(const std::string& tag) : scratch("launcher-" + tag), path(scratch.path()) {}
  std::filesystem::path write(const std::string& name, const std::string& text) const {
    harness::write_file(path / name, text);
    return path / name;
  }
  // The file's text; "" while it does not exist yet (a launcher's output before its first line).
  std::string read(const std::string& name) const {
    std::error_code ec;
    return std::filesystem::exists(path / name, ec) ? harness::read_file(path / name) : "";
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
