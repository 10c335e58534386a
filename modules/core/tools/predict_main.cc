// bricklayer-predict: reads one stack (JSON) from FILE or stdin ("-") and prints one prediction (JSON).
// With --jsonl: one stack per line in, one result per line out, in the same order; a bad line gives
// {"error": "...", "line": N} on its line and the run goes on (exit status 1 at the end).
// Exit status: 0 for any valid stack whatever the verdict; 1 bad input or solver failure; 2 bad flags.
#include <fstream>
#include <iostream>
#include <sstream>

#include <nlohmann/json.hpp>

#include "bricklayer/common/flags.h"
#include "bricklayer/core/predict.h"

namespace {

using bricklayer::core::PredictOptions;

std::string predict_text(const std::string& text, const PredictOptions& options) {
  nlohmann::json input;
  try {
    input = nlohmann::json::parse(text);
  } catch (const nlohmann::json::exception& e) {
    throw bricklayer::core::StackError(std::string("not valid JSON: ") + e.what());
  }
  const auto stack = bricklayer::core::stack_from_json(input, options.limits);
  nlohmann::json out = bricklayer::core::to_json(bricklayer::core::predict(stack, options));
  if (const auto name = input.find("name"); name != input.end()) out["name"] = *name;  // echo the label
  return out.dump();
}

int Main(int argc, char** argv) {
  bricklayer::Flags flags("bricklayer-predict",
                          "Predicts whether a pile of blocks is balanced and which blocks start its collapse.\n"
                          "Input: {\"block_length\": 1, \"block_height\": 0.333, \"table_edge\": 0, \"blocks\": "
                          "[{\"id\": 7, \"row\": 0, \"x\": -0.4}, ...]}");
  flags.add("annotator", "exact", "exact | paper | balance");
  flags.add("solver", "clp", "LP backend of the paper and balance annotators (and of --lp-first): clp | nlopt");
  flags.add("qp", "nnls", "exact annotator's QP: nnls | nlopt");
  flags.add("max-blocks", "2000", "reject stacks with more blocks than this");
  flags.add("position-tolerance", "0",
            "block lengths a position may be off (measured stacks): contact intervals widened by this at both ends");
  flags.add_bool("jsonl", "one stack per input line, one result per output line");
  flags.add_bool("lp-first", "exact annotator: ask the LP backend (--solver) whether the pile is balanced before the QP");
  flags.add_positional("FILE", "stack file, or - for stdin");
  if (!flags.parse(argc, argv)) return 0;

  PredictOptions options;
  try {
    options.annotator = bricklayer::core::parse_annotator(flags.get("annotator"));
    options.qp = bricklayer::core::parse_qp_method(flags.get("qp"));
  } catch (const std::invalid_argument& e) {
    throw bricklayer::FlagError(e.what());
  }
  options.solver = flags.get("solver");
  options.lp_first = flags.get_bool("lp-first");
  options.position_tolerance = flags.get_double("position-tolerance");
  if (!(options.position_tolerance >= 0.0 && options.position_tolerance <= bricklayer::core::kMaxPositionTolerance)) {
    throw bricklayer::FlagError("--position-tolerance must be in [0, " +
                                std::to_string(bricklayer::core::kMaxPositionTolerance) + "]");
  }
  if (options.solver != "clp" && options.solver != "nlopt") {
    throw bricklayer::FlagError("--solver: unknown solver \"" + options.solver + "\" (expected clp or nlopt)");
  }
  const int64_t max_blocks = flags.get_int("max-blocks");
  if (max_blocks < 0) throw bricklayer::FlagError("--max-blocks must be >= 0");
  options.limits.max_blocks = static_cast<size_t>(max_blocks);

  const std::string path = flags.positional().at(0);
  std::ifstream file;
  if (path != "-") {
    file.open(path);
    if (!file) throw std::runtime_error("cannot open " + path);
  }
  std::istream& in = path == "-" ? std::cin : file;

  if (!flags.get_bool("jsonl")) {
    std::stringstream buffer;
    buffer << in.rdbuf();
    std::cout << predict_text(buffer.str(), options) << "\n";
    return 0;
  }
  int status = 0;
  std::string line;
  int64_t number = 0;
  while (std::getline(in, line)) {
    ++number;
    if (line.find_first_not_of(" \t\r") == std::string::npos) continue;
    try {
      std::cout << predict_text(line, options) << "\n";
    } catch (const std::exception& e) {
      std::cout << nlohmann::json{{"error", e.what()}, {"line", number}}.dump() << "\n";
      status = 1;
    }
    std::cout.flush();
  }
  return status;
}

}  // namespace

int main(int argc, char** argv) { return bricklayer::run_main("bricklayer-predict", &Main, argc, argv); }
