// A built program started by a test: by target name (build/bin/NAME), its stderr (and stdout)
// captured in a scratch file, stopped (SIGTERM, then SIGKILL) when the test ends, never left behind.
#pragma once

#include <chrono>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "bricklayer/launcher/process.h"
#include "scratch.h"

namespace bricklayer::harness {

struct ProgramOptions {
  std::vector<std::string> env;  // "NAME=value" added to the environment
  std::string cwd;               // "" = the test's
};

class Program {
 public:
  // Starts build/bin/<target> (or an absolute path) with args. Throws when it cannot be started.
  Program(const std::string& target, std::vector<std::string> args = {}, ProgramOptions options = {});
  ~Program();
  Program(Program&&) = default;
  Program& operator=(Program&&) = default;

  pid_t pid() const { return process_.pid(); }
  bool running() { return process_.running(); }
  // The exit status once it has exited within timeout; nullopt while it runs.
  std::optional<launcher::ExitStatus> wait_exit(std::chrono::milliseconds timeout);
  // SIGTERM, up to 5 s, then SIGKILL; how it ended.
  launcher::ExitStatus stop();
  void signal(int sig) { process_.signal(sig); }

  // What it wrote so far.
  std::string stderr_text() const;
  std::string stdout_text() const;
  const std::string& target() const { return target_; }

 private:
  std::string target_;
  std::unique_ptr<ScratchDir> dir_;
  launcher::Process process_;
};

// Runs a program to its end (killed after timeout) and returns its exit status and output.
struct Ran {
  launcher::ExitStatus status;
  std::string out, err;
  bool timed_out = false;
};
Ran run_program(const std::string& target, std::vector<std::string> args,
                std::chrono::milliseconds timeout = std::chrono::seconds(30), ProgramOptions options = {});

}  // namespace bricklayer::harness
