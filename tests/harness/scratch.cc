#include "scratch.h"

#include <unistd.h>

#include <atomic>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <stdexcept>

namespace bricklayer::harness {
namespace fs = std::filesystem;

ScratchDir::ScratchDir(const std::string& label) {
  static std::atomic<int> counter{0};
  path_ = fs::temp_directory_path() /
          ("bricklayer-" + label + "-" + std::to_string(::getpid()) + "-" + std::to_string(counter++));
  fs::remove_all(path_);
  fs::create_directories(path_);
}

ScratchDir::~ScratchDir() {
  const char* keep = std::getenv("BRICKLAYER_KEEP_SCRATCH");
  if (keep && std::string(keep) == "1") return;
  std::error_code ec;
  fs::remove_all(path_, ec);
}

std::string read_file(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::runtime_error("cannot read '" + path.string() + "'");
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

void write_file(const fs::path& path, const std::string& text) {
  if (path.has_parent_path()) fs::create_directories(path.parent_path());
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out << text;
  if (!out) throw std::runtime_error("cannot write '" + path.string() + "'");
}

fs::path source_dir() { return BRICKLAYER_SOURCE_DIR; }
fs::path binary_dir() { return BRICKLAYER_BINARY_DIR; }
std::string program_path(const std::string& target) { return (binary_dir() / "bin" / target).string(); }

}  // namespace bricklayer::harness
