// bricklayer-report: how the exhibit did, as a page with plots, from recorded bus logs (a day, a
// range: every file in order). Reads LCM log files only (no bus); plots are drawn by gnuplot.
// Output: DIR/index.html (self-contained), DIR/plots/*.png (+ their data and gnuplot scripts),
// DIR/report.json (every number on the page). Exit 0; 1 when the log is damaged (the report of what
// could be read is written first) or the report cannot be written; 2 on bad usage.
#include <iostream>

#include "bricklayer/common/flags.h"
#include "bricklayer/inspect/decoded_log.h"
#include "bricklayer/inspect/gnuplot.h"
#include "bricklayer/inspect/report_numbers.h"
#include "bricklayer/inspect/report_page.h"
#include "bricklayer/inspect/report_stats.h"

namespace {

using namespace bricklayer;
using namespace bricklayer::inspect;

int Main(int argc, char** argv) {
  Flags flags("bricklayer-report",
              "Writes a report of recorded LCM logs: rounds and their MAX, the distribution of scores, piles that fell\n"
              "and how long red lasted, end-to-end latency percentiles over time, frame rates, module restarts and\n"
              "errors, disk use. DIR/index.html is one self-contained page; DIR/report.json holds its numbers.");
  flags.add_positional_list("LOG", "log files, in order (a split log, a day)");
  flags.add("out", "", "output folder (created when missing); required");
  flags.add("gnuplot", "gnuplot", "the gnuplot program that draws the plots");
  flags.add_bool("quiet", "no progress lines");
  flags.add("progress-seconds", "2", "seconds between progress lines (shown once a run takes that long)");
  if (!flags.parse(argc, argv)) return 0;
  if (flags.get("out").empty()) throw FlagError("--out DIR is required");
  const std::vector<std::string>& logs = flags.positional();

  ReportStats stats;
  ReadSummary summary;
  try {
    summary = read_decoded(logs, builtin_types(), [&](const DecodedEvent& e) { stats.add(e); },
                           flags.get_bool("quiet") ? "" : "bricklayer-report",
        flags.get_double("progress-seconds"));
  } catch (const LogOpenError& e) {
    std::cerr << "bricklayer-report: error: " << e.what() << "\n";
    return 1;
  }
  stats.finish();
  std::cerr << "bricklayer-report: " << summary.describe() << "\n";
  if (stats.events() == 0) {
    std::cerr << "bricklayer-report: error: no event could be read from the log; nothing to report\n";
    return 1;
  }
  try {
    write_report(stats, report_numbers(stats, summary, logs), flags.get("out"), ReportOptions{flags.get("gnuplot")});
  } catch (const std::exception& e) {
    std::cerr << "bricklayer-report: error: " << e.what() << "\n";
    return 1;
  }
  std::cerr << "bricklayer-report: wrote " << flags.get("out") << "/index.html\n";
  if (summary.damaged()) {
    std::cerr << "bricklayer-report: error: the log is damaged (" << summary.problems.size() << " torn or corrupt stretch(es), "
              << summary.malformed << " malformed message(s)); the report covers what could be read\n";
    return 1;
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) { return bricklayer::run_main("bricklayer-report", &Main, argc, argv); }
