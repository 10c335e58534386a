// Starting and stopping the project's programs from tests: fork/exec with a bounded wait, so a
// process test can never hang the suite.
#pragma once

#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <string>
#include <vector>

namespace bricklayer::test {

// The built program's path (build/bin/NAME).
inline std::string program(const std::string& name) { return std::string(BRICKLAYER_BINARY_DIR) + "/bin/" + name; }

// Starts args[0] with the arguments; returns its pid (exec failure: the child exits 127).
inline pid_t spawn(std::vector<std::string> args) {
  pid_t pid = fork();
  if (pid == 0) {
    std::vector<char*> argv;
    for (auto& a : args) argv.push_back(a.data());
    argv.push_back(nullptr);
    execv(argv[0], argv.data());
    _exit(127);
  }
  return pid;
}

// The exit code, -1 when killed by a signal, -2 when it had to be killed after `seconds`.
inline int wait_exit(pid_t pid, int seconds) {
  for (int i = 0; i < seconds * 50; ++i) {
    int status = 0;
    if (waitpid(pid, &status, WNOHANG) == pid) return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    usleep(20000);
  }
  kill(pid, SIGKILL);
  waitpid(pid, nullptr, 0);
  return -2;
}

// SIGTERM, then the exit code (or SIGKILL after 5 s).
inline int stop(pid_t pid) {
  kill(pid, SIGTERM);
  return wait_exit(pid, 5);
}

}  // namespace bricklayer::test
