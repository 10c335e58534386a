// bricklayer-report's output folder: index.html, one self-contained page (plots embedded as PNG data,
// no script, no external file), the plots as PNG files with their gnuplot scripts and data in plots/,
// and report.json with every number the page shows.
#pragma once

#include <string>

#include "bricklayer/inspect/report_stats.h"

namespace bricklayer::inspect {

struct ReportOptions {
  std::string gnuplot = "gnuplot";
};

// Throws PlotError (gnuplot) or std::runtime_error (files) on failure.
void write_report(const ReportStats& stats, const Json& numbers, const std::string& dir, const ReportOptions& options);

// Text made safe inside HTML elements and attribute values.
std::string html_escape(const std::string& text);

}  // namespace bricklayer::inspect
