#include "bricklayer/inspect/gnuplot.h"

#include <fcntl.h>
#include <spawn.h>
#include <sys/wait.h>

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>

extern char** environ;

namespace bricklayer::inspect {

namespace fs = std::filesystem;

std::string render_plot(const Plot& plot, const std::string& dir, const std::string& gnuplot_program) {
  for (const auto& [file, text] : plot.data) {
    std::ofstream out(fs::path(dir) / file, std::ios::trunc);
    out << text;
    if (!out) throw PlotError("cannot write " + (fs::path(dir) / file).string());
  }
  const std::string png = plot.name + ".png", script = plot.name + ".gp", log = plot.name + ".log";
  {
    std::ofstream out(fs::path(dir) / script, std::ios::trunc);
    out << "set terminal pngcairo noenhanced size " << plot.width << "," << plot.height
        << " font 'DejaVu Sans,10' background rgb 'white'\n"
        << "set output '" << png << "'\n"
        << plot.script << "\n";
    if (!out) throw PlotError("cannot write " + (fs::path(dir) / script).string());
  }
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  const std::string log_path = (fs::path(dir) / log).string();
  posix_spawn_file_actions_addopen(&actions, 2, log_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  posix_spawn_file_actions_addopen(&actions, 1, "/dev/null", O_WRONLY, 0);
  const std::string script_path = (fs::path(dir) / script).string();
  // gnuplot resolves the data files relative to its working directory: run it in `dir`.
  std::string command = "cd \"$1\" && exec \"$2\" \"$3\"";
  std::vector<std::string> args = {"/bin/sh", "-c", command, "sh", dir, gnuplot_program, script};
  std::vector<char*> argv;
  for (auto& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);
  pid_t pid;
  int rc = posix_spawn(&pid, "/bin/sh", &actions, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  if (rc != 0) throw PlotError("cannot start /bin/sh for gnuplot: " + std::string(std::strerror(rc)));
  int status = 0;
  while (::waitpid(pid, &status, 0) < 0 && errno == EINTR) {
  }
  std::ifstream in(log_path);
  std::stringstream messages;
  messages << in.rdbuf();
  if (!WIFEXITED(status) || WEXITSTATUS(status) != 0 || !fs::exists(fs::path(dir) / png) ||
      fs::file_size(fs::path(dir) / png) == 0) {
    if (WIFEXITED(status) && WEXITSTATUS(status) == 127)
      throw PlotError("gnuplot was not found (" + gnuplot_program + "): install gnuplot-nox (launch/setup does)");
    throw PlotError("gnuplot failed on " + script_path + ": " + messages.str());
  }
  return (fs::path(dir) / png).string();
}

}  // namespace bricklayer::inspect
