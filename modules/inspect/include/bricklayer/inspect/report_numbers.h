// Every number bricklayer-report shows, as one JSON document (report.json beside the page): the page
// is drawn from it, tools can read it, and the tests recompute it from the CSV export.
#pragma once

#include <string>
#include <vector>

#include "bricklayer/inspect/decoded_log.h"
#include "bricklayer/inspect/report_stats.h"

namespace bricklayer::inspect {

Json report_numbers(const ReportStats& stats, const ReadSummary& read, const std::vector<std::string>& logs);

}  // namespace bricklayer::inspect
