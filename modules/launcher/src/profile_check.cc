#include "bricklayer/launcher/profile_check.h"

#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <sstream>

namespace bricklayer::launcher {
namespace {

namespace fs = std::filesystem;

struct Output {
  bool finished = false;
  ExitStatus status;
  std::string text;  // stdout and stderr together
};

// Runs argv in cwd with the bus URL, up to 10 s; what it printed.
Output run_captured(const std::vector<std::string>& argv, const SupervisorOptions& options) {
  static int serial = 0;
  const fs::path out = fs::temp_directory_path() /
                       ("bricklayer-launch-check-" + std::to_string(::getpid()) + "-" + std::to_string(serial++));
  SpawnOptions o;
  o.cwd = options.root;
  o.stdout_path = out.string();
  o.merge_stderr = true;
  o.env = {"LCM_DEFAULT_URL=" + options.lcm_url};
  Output result;
  try {
    Process p = Process::spawn(argv, o);
    if (auto st = p.wait_for(std::chrono::seconds(10))) {
      result.finished = true;
      result.status = *st;
    }
  } catch (const std::exception& e) {
    result.text = e.what();
  }
  std::ifstream in(out);
  std::stringstream text;
  text << in.rdbuf();
  result.text += text.str();
  std::error_code ec;
  fs::remove(out, ec);
  return result;
}

fs::path under_root(const std::string& path, const SupervisorOptions& options) {
  return fs::path(path).is_absolute() ? fs::path(path) : fs::path(options.root) / path;
}

}  // namespace

const std::vector<std::string> kInputFileFlags = {"--scenario", "--calibration", "--font", "--board", "--video", "--images"};

FileCheckReport check_module_files(const LaunchPlan& plan, const SupervisorOptions& options) {
  FileCheckReport report;
  for (const auto& [spec, argv] : plan.processes) {
    const std::string who = "module '" + spec.name + "'";
    for (const std::string& need : spec.needs) {
      std::error_code ec;
      if (!fs::exists(under_root(need, options), ec))
        report.problems.push_back(who + " needs '" + need + "' (the profile's needs), which does not exist under " +
                                  options.root);
    }
    if (argv.empty() || argv[0].empty()) continue;
    const Output help = run_captured({argv[0], "--help"}, options);
    if (help.text.find("--check-config") != std::string::npos) {
      std::vector<std::string> check = argv;
      check.push_back("--check-config");
      const Output r = run_captured(check, options);
      if (!r.finished) {
        report.problems.push_back(who + ": '" + argv[0] + " ... --check-config' did not finish within 10 s");
      } else if (!r.status.clean()) {
        std::string lines;
        std::istringstream in(r.text);
        for (std::string line; std::getline(in, line);)
          if (line.find("error") != std::string::npos) lines += "\n    " + line;
        report.problems.push_back(who + ": its own check failed (" + r.status.describe() + ")" +
                                  (lines.empty() ? "\n    " + r.text : lines));
      } else {
        report.notes.push_back(spec.name + ": flags and files checked by " + fs::path(argv[0]).filename().string() +
                               " --check-config");
      }
      continue;
    }
    int checked = 0;
    for (size_t i = 1; i < argv.size(); ++i) {
      std::string flag = argv[i], value;
      if (const auto eq = flag.find('='); eq != std::string::npos) {
        value = flag.substr(eq + 1);
        flag = flag.substr(0, eq);
      } else if (i + 1 < argv.size()) {
        value = argv[i + 1];
      }
      if (std::find(kInputFileFlags.begin(), kInputFileFlags.end(), flag) == kInputFileFlags.end()) continue;
      // --board also takes inline JSON; only a value that names a .json file is one.
      if (value.empty() || value.rfind("--", 0) == 0 || (flag == "--board" && value.front() == '{')) continue;
      ++checked;
      std::error_code ec;
      if (!fs::exists(under_root(value, options), ec))
        report.problems.push_back(who + ": " + flag + " " + value + ": no such file under " + options.root);
    }
    report.notes.push_back(spec.name + ": " + std::to_string(checked) + " input file" + (checked == 1 ? "" : "s") +
                           " of its command line checked (" + fs::path(argv[0]).filename().string() +
                           " has no --check-config)");
  }
  return report;
}

}  // namespace bricklayer::launcher
