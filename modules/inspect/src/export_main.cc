// bricklayer-export: a recorded bus log as files other tools open. One pass over the log, any
// combination of outputs:
//   --csv DIR     one CSV per message kind (stacks and predictions one row per block), index.csv
//   --jsonl DIR   the same as JSON lines
//   --mcap FILE   the whole log as MCAP for Foxglove (written by @mcap/core under Node.js)
// Reads LCM log files only (no bus). Exit 0; 1 when the log is damaged (torn or corrupt: everything
// readable is written first) or an output fails; 2 on bad usage.
#include <iostream>
#include <memory>
#include <optional>

#include "bricklayer/common/flags.h"
#include "bricklayer/inspect/decoded_log.h"
#include "bricklayer/inspect/file_export.h"
#include "bricklayer/inspect/lcm_schema.h"
#include "bricklayer/inspect/mcap_export.h"

namespace {

using namespace bricklayer;
using namespace bricklayer::inspect;

int Main(int argc, char** argv) {
  Flags flags("bricklayer-export",
              "Exports recorded LCM logs (bricklayer-logger's files, in order) as CSV, JSON lines and/or MCAP.\n"
              "Every message type is decoded from the .lcm definitions built into this program and recognised\n"
              "by its fingerprint; times are given as utime (microseconds) and as UTC wall-clock text.");
  flags.add_positional_list("LOG", "log files, in order (a split log, a day)");
  flags.add("csv", "", "write one CSV file per message kind into this folder");
  flags.add("jsonl", "", "write one JSON-lines file per message kind into this folder");
  flags.add("mcap", "", "write the whole log as this MCAP file (camera and projector images as foxglove.CompressedImage)");
  flags.add("node", "node", "the Node.js program that runs the MCAP writer");
  flags.add("mcap-js", default_mcap_js_dir(), "folder of the MCAP writer script and its node_modules");
  flags.add_bool("quiet", "no progress lines");
  flags.add("progress-seconds", "2", "seconds between progress lines (shown once a run takes that long)");
  if (!flags.parse(argc, argv)) return 0;
  std::vector<std::string> logs = flags.positional();
  if (flags.get("csv").empty() && flags.get("jsonl").empty() && flags.get("mcap").empty())
    throw FlagError("nothing to do: give --csv DIR, --jsonl DIR and/or --mcap FILE");

  const LcmTypeSet& types = builtin_types();
  std::unique_ptr<FileExport> csv, jsonl;
  std::unique_ptr<McapExport> mcap;
  try {
    if (!flags.get("csv").empty()) csv = std::make_unique<FileExport>(types, flags.get("csv"), FileExport::Format::kCsv);
    if (!flags.get("jsonl").empty())
      jsonl = std::make_unique<FileExport>(types, flags.get("jsonl"), FileExport::Format::kJsonl);
    if (!flags.get("mcap").empty())
      mcap = std::make_unique<McapExport>(types, flags.get("mcap"), McapExport::Options{flags.get("node"), flags.get("mcap-js")});
  } catch (const std::runtime_error& e) {
    std::cerr << "bricklayer-export: error: " << e.what() << "\n";
    return 1;
  }

  ReadSummary summary;
  std::string failure;
  try {
    summary = read_decoded(
        logs, types,
        [&](const DecodedEvent& e) {
          if (csv) csv->add(e);
          if (jsonl) jsonl->add(e);
          if (mcap) mcap->add(e);
        },
        flags.get_bool("quiet") ? "" : "bricklayer-export",
        flags.get_double("progress-seconds"));
  } catch (const LogOpenError& e) {
    failure = e.what();
  } catch (const std::runtime_error& e) {
    failure = e.what();
  }
  // Whatever happened, close what was written so it can be used.
  try {
    if (csv) csv->finish();
    if (jsonl) jsonl->finish();
    if (mcap) mcap->finish();
  } catch (const std::runtime_error& e) {
    failure += (failure.empty() ? "" : "; ") + std::string(e.what());
  }
  std::cerr << "bricklayer-export: " << summary.describe() << "\n";
  if (csv) std::cerr << "  csv: " << csv->kinds().size() << " files in " << flags.get("csv") << "\n";
  if (jsonl) std::cerr << "  jsonl: " << jsonl->kinds().size() << " files in " << flags.get("jsonl") << "\n";
  if (mcap) std::cerr << "  mcap: " << mcap->messages() << " messages on " << mcap->channels() << " channels in " << flags.get("mcap") << "\n";
  if (!failure.empty()) {
    std::cerr << "bricklayer-export: error: " << failure << "\n";
    return 1;
  }
  if (summary.damaged()) {
    std::cerr << "bricklayer-export: error: the log is damaged (" << summary.problems.size() << " torn or corrupt stretch(es), "
              << summary.malformed << " malformed message(s)); everything readable was written\n";
    return 1;
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) { return bricklayer::run_main("bricklayer-export", &Main, argc, argv); }
