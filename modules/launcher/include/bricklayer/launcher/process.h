// A child process started with fork/execve: its own process group (so a stop reaches everything it
// started), killed with its parent (PR_SET_PDEATHSIG), stopped with SIGTERM and a deadline, then SIGKILL.
// Used by bricklayer-launch and by the tests that drive real processes.
#pragma once

#include <sys/types.h>

#include <chrono>
#include <optional>
#include <string>
#include <vector>

namespace bricklayer::launcher {

struct SpawnOptions {
  std::string cwd;                       // working directory of the child ("" = inherit)
  std::vector<std::string> env;          // "NAME=value" entries added to (or replacing in) the environment
  std::string stdout_path;               // redirect stdout to this file (truncated); "" = inherit
  std::string stderr_path;               // redirect stderr to this file (truncated); "" = inherit
  bool merge_stderr = false;             // stderr goes where stdout goes
  // The launcher's service holds CAP_NET_ADMIN as an ambient capability (launch/setup) for its own
  // `ip route replace` only: every other child starts with the ambient set cleared.
  bool keep_ambient_capabilities = false;
};

// How a process ended, decoded from waitpid's status.
struct ExitStatus {
  int code = 0;     // exit code when exited normally
  int signal = 0;   // terminating signal, 0 when it exited
  std::string describe() const;  // "exit code 1", "killed by signal 9 (Killed)"
  bool clean() const { return signal == 0 && code == 0; }
};

class Process {
 public:
  Process() = default;
  // Starts argv[0] (a path: no PATH search, see find_program) with argv. Throws std::runtime_error
  // when fork fails or the program is not executable.
  static Process spawn(const std::vector<std::string>& argv, const SpawnOptions& options = {});

  Process(Process&& other) noexcept;
  Process& operator=(Process&& other) noexcept;
  Process(const Process&) = delete;
  Process& operator=(const Process&) = delete;
  ~Process();  // a still-running child is killed (SIGKILL to its group) and reaped

  pid_t pid() const { return pid_; }
  bool started() const { return pid_ > 0; }
  // Reaps without blocking; true while the child has not exited.
  bool running();
  // Waits up to timeout for the child to exit; the exit status, or nullopt when still running.
  std::optional<ExitStatus> wait_for(std::chrono::milliseconds timeout);
  std::optional<ExitStatus> exit_status() const { return exit_; }
  // Sends sig to the child's whole process group.
  void signal(int sig);
  // SIGTERM, wait up to deadline, then SIGKILL. Returns how it ended.
  ExitStatus stop(std::chrono::milliseconds deadline);

 private:
  pid_t pid_ = -1;
  std::optional<ExitStatus> exit_;
};

// Resolves a program name: a name containing '/' is taken relative to base_dir (unless absolute);
// a bare name is looked up in each of search_dirs, then in PATH. Returns "" when not found/executable.
std::string find_program(const std::string& name, const std::string& base_dir,
                         const std::vector<std::string>& search_dirs);

}  // namespace bricklayer::launcher
