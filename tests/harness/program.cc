#include "program.h"

#include <csignal>

namespace bricklayer::harness {

Program::Program(const std::string& target, std::vector<std::string> args, ProgramOptions options)
    : target_(target), dir_(std::make_unique<ScratchDir>("program")) {
  std::vector<std::string> argv{target.find('/') == std::string::npos ? program_path(target) : target};
  argv.insert(argv.end(), args.begin(), args.end());
  launcher::SpawnOptions o;
  o.env = std::move(options.env);
  o.cwd = std::move(options.cwd);
  o.stdout_path = (*dir_ / "stdout").string();
  o.stderr_path = (*dir_ / "stderr").string();
  process_ = launcher::Process::spawn(argv, o);
}

Program::~Program() {
  if (process_.started() && process_.running()) process_.stop(std::chrono::seconds(5));
}

std::optional<launcher::ExitStatus> Program::wait_exit(std::chrono::milliseconds timeout) {
  return process_.wait_for(timeout);
}

launcher::ExitStatus Program::stop() {
  if (process_.running()) return process_.stop(std::chrono::seconds(5));
  return *process_.exit_status();
}

std::string Program::stderr_text() const { return read_file(*dir_ / "stderr"); }
std::string Program::stdout_text() const { return read_file(*dir_ / "stdout"); }

Ran run_program(const std::string& target, std::vector<std::string> args, std::chrono::milliseconds timeout,
                ProgramOptions options) {
  Program p(target, std::move(args), std::move(options));
  Ran ran;
  if (auto st = p.wait_exit(timeout)) {
    ran.status = *st;
  } else {
    ran.timed_out = true;
    ran.status = p.stop();
  }
  ran.out = p.stdout_text();
  ran.err = p.stderr_text();
  return ran;
}

}  // namespace bricklayer::harness
