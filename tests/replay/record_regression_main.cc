// bricklayer-replay-record-regression OUT.lcm [SECONDS]: records the regression log kept with the
// tests (rig_runs.h, record_regression_run): the real simcam, vision, prediction, planner and
// projection nodes on the in-process rig. Make it again after a change that is meant, or rewrite its
// expected outputs with bricklayer-replay --update (modules/replay/README.md).
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <iostream>

#include "rig_runs.h"

int main(int argc, char** argv) {
  if (argc < 2 || argc > 3) {
    std::cerr << "usage: bricklayer-replay-record-regression OUT.lcm [SECONDS (9)]\n";
    return 2;
  }
  try {
    const double seconds = argc == 3 ? std::atof(argv[2]) : 9;
    if (!(seconds > 0 && seconds <= 60)) throw std::invalid_argument("SECONDS must be in (0, 60]");
    const int64_t events = bricklayer::test::record_regression_run(argv[1], seconds);
    std::cout << "wrote " << argv[1] << ": " << events << " events, " << std::filesystem::file_size(argv[1]) << " bytes\n";
  } catch (const std::exception& e) {
    std::cerr << "bricklayer-replay-record-regression: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
