#include "bricklayer/launcher/process.h"

#include <fcntl.h>
#include <signal.h>
#include <sys/prctl.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <map>
#include <stdexcept>
#include <thread>

extern char** environ;

namespace bricklayer::launcher {
namespace {

ExitStatus decode(int status) {
  ExitStatus out;
  if (WIFEXITED(status)) out.code = WEXITSTATUS(status);
  if (WIFSIGNALED(status)) out.signal = WTERMSIG(status);
  return out;
}

bool is_executable(const std::string& path) {
  struct stat st {};
  return !path.empty() && ::stat(path.c_str(), &st) == 0 && S_ISREG(st.st_mode) && ::access(path.c_str(), X_OK) == 0;
}

}  // namespace

std::string ExitStatus::describe() const {
  if (signal != 0) {
    const char* name = strsignal(signal);
    return "killed by signal " + std::to_string(signal) + " (" + (name ? name : "?") + ")";
  }
  return "exit code " + std::to_string(code);
}

Process Process::spawn(const std::vector<std::string>& argv, const SpawnOptions& options) {
  if (argv.empty()) throw std::runtime_error("spawn: empty command line");
  if (!is_executable(argv[0])) throw std::runtime_error("spawn: '" + argv[0] + "' is not an executable file");

  // Everything the child needs is prepared here: between fork and exec only async-signal-safe calls.
  std::vector<char*> args;
  for (const auto& a : argv) args.push_back(const_cast<char*>(a.c_str()));
  args.push_back(nullptr);

  std::map<std::string, std::string> env;
  for (char** e = environ; e && *e; ++e) {
    std::string kv = *e;
    auto eq = kv.find('=');
    if (eq != std::string::npos) env[kv.substr(0, eq)] = kv.substr(eq + 1);
  }
  for (const auto& kv : options.env) {
    auto eq = kv.find('=');
    if (eq == std::string::npos) throw std::runtime_error("spawn: environment entry '" + kv + "' has no '='");
    env[kv.substr(0, eq)] = kv.substr(eq + 1);
  }
  std::vector<std::string> env_strings;
  for (const auto& [k, v] : env) env_strings.push_back(k + "=" + v);
  std::vector<char*> envp;
  for (auto& s : env_strings) envp.push_back(s.data());
  envp.push_back(nullptr);

  const pid_t parent = ::getpid();
  pid_t pid = ::fork();
  if (pid < 0) throw std::runtime_error(std::string("fork failed: ") + std::strerror(errno));
  if (pid == 0) {
    ::setpgid(0, 0);
    ::prctl(PR_SET_PDEATHSIG, SIGTERM);
    if (::getppid() != parent) _exit(126);  // the parent died before prctl took effect
    if (!options.keep_ambient_capabilities) ::prctl(PR_CAP_AMBIENT, PR_CAP_AMBIENT_CLEAR_ALL, 0, 0, 0);
    // Signal dispositions set to "ignore" survive exec: give the child the defaults back.
    struct sigaction dfl {};
    dfl.sa_handler = SIG_DFL;
    for (int s : {SIGPIPE, SIGINT, SIGTERM, SIGHUP, SIGCHLD}) ::sigaction(s, &dfl, nullptr);
    sigset_t none;
    sigemptyset(&none);
    ::sigprocmask(SIG_SETMASK, &none, nullptr);
    if (!options.cwd.empty() && ::chdir(options.cwd.c_str()) != 0) _exit(126);
    if (!options.stdout_path.empty()) {
      int fd = ::open(options.stdout_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
      if (fd < 0) _exit(126);
      ::dup2(fd, 1);
    }
    if (options.merge_stderr) {
      ::dup2(1, 2);
    } else if (!options.stderr_path.empty()) {
      int fd = ::open(options.stderr_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
      if (fd < 0) _exit(126);
      ::dup2(fd, 2);
    }
    ::execve(args[0], args.data(), envp.data());
    const char msg[] = "spawn: execve failed\n";
    (void)!::write(2, msg, sizeof(msg) - 1);
    _exit(127);
  }
  ::setpgid(pid, pid);  // also from the parent, so signal() cannot race the child's own setpgid
  Process p;
  p.pid_ = pid;
  return p;
}

Process::Process(Process&& other) noexcept : pid_(other.pid_), exit_(other.exit_) { other.pid_ = -1; }

Process& Process::operator=(Process&& other) noexcept {
  if (this != &other) {
    if (pid_ > 0 && !exit_) {
      signal(SIGKILL);
      wait_for(std::chrono::milliseconds(2000));
    }
    pid_ = other.pid_;
    exit_ = other.exit_;
    other.pid_ = -1;
  }
  return *this;
}

Process::~Process() {
  if (pid_ > 0 && !exit_) {
    signal(SIGKILL);
    wait_for(std::chrono::milliseconds(2000));
  }
}

bool Process::running() {
  if (pid_ <= 0 || exit_) return false;
  int status = 0;
  pid_t r = ::waitpid(pid_, &status, WNOHANG);
  if (r == pid_) {
    exit_ = decode(status);
    return false;
  }
  if (r < 0 && errno == ECHILD) {  // reaped elsewhere: treat as gone
    exit_ = ExitStatus{-1, 0};
    return false;
  }
  return true;
}

std::optional<ExitStatus> Process::wait_for(std::chrono::milliseconds timeout) {
  auto deadline = std::chrono::steady_clock::now() + timeout;
  while (running()) {
    if (std::chrono::steady_clock::now() >= deadline) return std::nullopt;
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  return exit_;
}

void Process::signal(int sig) {
  if (pid_ <= 0 || exit_) return;
  if (::kill(-pid_, sig) != 0) ::kill(pid_, sig);
}

ExitStatus Process::stop(std::chrono::milliseconds deadline) {
  if (!running()) return exit_.value_or(ExitStatus{});
  signal(SIGTERM);
  if (auto st = wait_for(deadline)) return *st;
  signal(SIGKILL);
  if (auto st = wait_for(std::chrono::milliseconds(5000))) return *st;
  return ExitStatus{-1, SIGKILL};
}

std::string find_program(const std::string& name, const std::string& base_dir,
                         const std::vector<std::string>& search_dirs) {
  if (name.empty()) return "";
  if (name.find('/') != std::string::npos) {
    std::string path = (name[0] == '/' || base_dir.empty()) ? name : base_dir + "/" + name;
    return is_executable(path) ? path : "";
  }
  for (const auto& dir : search_dirs) {
    std::string path = dir + "/" + name;
    if (is_executable(path)) return path;
  }
  if (const char* path_env = std::getenv("PATH")) {
    std::string all = path_env;
    size_t start = 0;
    while (start <= all.size()) {
      size_t end = all.find(':', start);
      if (end == std::string::npos) end = all.size();
      std::string dir = all.substr(start, end - start);
      if (!dir.empty() && is_executable(dir + "/" + name)) return dir + "/" + name;
      start = end + 1;
    }
  }
  return "";
}

}  // namespace bricklayer::launcher
