// bricklayer-launch --check's look at the files a profile's modules will read: a missing scenario,
// calibration or font is found before the exhibit opens, not when a module crash-loops on it.
#pragma once

#include <string>
#include <vector>

#include "bricklayer/launcher/supervisor.h"

namespace bricklayer::launcher {

struct FileCheckReport {
  std::vector<std::string> problems;  // each names the module and the file; the profile cannot run as it is
  std::vector<std::string> notes;     // what was checked how, for each module
};

// For each process of the plan, in this order:
//  1. the profile's "needs" (paths relative to the root) must exist;
//  2. a program that offers --check-config (every runtime node) is run with its command line and
//     --check-config in the root: it checks its flags and every file they name, and starts nothing;
//  3. otherwise the values of the input-file flags the shipped programs share (kInputFileFlags) must
//     name existing files.
FileCheckReport check_module_files(const LaunchPlan& plan, const SupervisorOptions& options);

// Flags whose value is a file a module reads at start (used where a program cannot check itself).
extern const std::vector<std::string> kInputFileFlags;

}  // namespace bricklayer::launcher
