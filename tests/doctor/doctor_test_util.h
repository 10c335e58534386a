// Running the real bricklayer-doctor from tests: its output, exit code and the line of one check.
#pragma once

#include <fcntl.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "harness/scratch.h"

namespace bricklayer::test {

struct DoctorRun {
  int code = -3;    // exit code; -1 killed by a signal, -2 timed out
  std::string out;  // stdout and stderr
};

// Runs argv (argv[0] a path) with extra environment entries ("NAME=value"; "NAME=" removes NAME,
// which harness::run_program cannot: the doctor tells an unset DISPLAY from an empty one), for at most
// `seconds`, its stdout and stderr in one pipe so the lines keep their order.
inline DoctorRun run_capture(std::vector<std::string> argv, const std::vector<std::string>& env = {}, int seconds = 60) {
  int pipefd[2];
  if (pipe(pipefd) != 0) return {};
  pid_t pid = fork();
  if (pid == 0) {
    dup2(pipefd[1], 1);
    dup2(pipefd[1], 2);
    close(pipefd[0]);
    close(pipefd[1]);
    for (const auto& e : env) {
      auto eq = e.find('=');
      if (eq + 1 == e.size())
        unsetenv(e.substr(0, eq).c_str());
      else
        setenv(e.substr(0, eq).c_str(), e.substr(eq + 1).c_str(), 1);
    }
    std::vector<char*> args;
    for (auto& a : argv) args.push_back(a.data());
    args.push_back(nullptr);
    execv(args[0], args.data());
    _exit(127);
  }
  close(pipefd[1]);
  fcntl(pipefd[0], F_SETFL, O_NONBLOCK);
  DoctorRun run;
  const auto end = std::chrono::steady_clock::now() + std::chrono::seconds(seconds);
  char buf[4096];
  for (;;) {
    ssize_t n = read(pipefd[0], buf, sizeof(buf));
    if (n > 0) {
      run.out.append(buf, static_cast<size_t>(n));
      continue;
    }
    int status = 0;
    if (waitpid(pid, &status, WNOHANG) == pid) {
      while ((n = read(pipefd[0], buf, sizeof(buf))) > 0) run.out.append(buf, static_cast<size_t>(n));
      run.code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
      break;
    }
    if (std::chrono::steady_clock::now() > end) {
      kill(pid, SIGKILL);
      waitpid(pid, nullptr, 0);
      run.code = -2;
      break;
    }
    usleep(10000);
  }
  close(pipefd[0]);
  return run;
}

inline DoctorRun run_doctor(std::vector<std::string> args, const std::vector<std::string>& env = {}, int seconds = 60) {
  args.insert(args.begin(), harness::program_path("bricklayer-doctor"));
  return run_capture(std::move(args), env, seconds);
}

// The line the doctor printed for check `name` ("" when there is none).
inline std::string check_line(const std::string& out, const std::string& name) {
  std::istringstream in(out);
  std::string line;
  while (std::getline(in, line)) {
    auto first = line.find(' ');
    if (first == std::string::npos) continue;
    auto start = line.find_first_not_of(' ', first);
    if (start != std::string::npos && line.compare(start, name.size() + 2, name + "  ") == 0) return line;
  }
  return "";
}
inline std::string severity(const std::string& line) { return line.substr(0, line.find(' ')); }

inline std::filesystem::path temp_dir(const std::string& name) {
  auto dir = std::filesystem::temp_directory_path() / ("bricklayer-doctor-test-" + name + "-" + std::to_string(getpid()));
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir;
}

inline std::string write_file(const std::filesystem::path& path, const std::string& text) {
  std::ofstream(path) << text;
  return path.string();
}

inline std::string shipped_profile(const std::string& name) {
  return std::string(BRICKLAYER_SOURCE_DIR) + "/launch/profiles/" + name + ".json";
}

}  // namespace bricklayer::test
