// Scratch folders and file helpers for tests.
#pragma once

#include <filesystem>
#include <string>

namespace bricklayer::harness {

// A fresh, empty folder for one test, removed when it goes out of scope (kept when the environment
// sets BRICKLAYER_KEEP_SCRATCH=1, to look at what a failing test left).
class ScratchDir {
 public:
  explicit ScratchDir(const std::string& label = "test");
  ~ScratchDir();
  ScratchDir(const ScratchDir&) = delete;
  ScratchDir& operator=(const ScratchDir&) = delete;

  const std::filesystem::path& path() const { return path_; }
  std::filesystem::path operator/(const std::string& name) const { return path_ / name; }
  std::string str() const { return path_.string(); }

 private:
  std::filesystem::path path_;
};

// The whole file; throws std::runtime_error naming it when it cannot be read.
std::string read_file(const std::filesystem::path& path);
// Creates or replaces the file (and its folders); throws std::runtime_error when it cannot.
void write_file(const std::filesystem::path& path, const std::string& text);

// Paths of the tree: the source root, the build folder, a built program (build/bin/NAME).
std::filesystem::path source_dir();
std::filesystem::path binary_dir();
std::string program_path(const std::string& target);

}  // namespace bricklayer::harness
