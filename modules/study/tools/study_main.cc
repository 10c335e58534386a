// bricklayer-study: the seed paper's study, offline parts.
//
//   bricklayer-study report [--csv FILE] [--tests-csv FILE] LOG...
//       Reads the study messages (BL_STUDY_SESSION, BL_STUDY_TRIAL, BL_STUDY_ANSWER) of every log and
//       prints Table 1 per condition and the F- and t-tests between conditions; --csv / --tests-csv write
//       the rows as CSV ("-" for stdout).
//   bricklayer-study minimum PROBLEM...
//       Computes the fewest added blocks of each stabilise problem, with a witness and how it was proven,
//       and checks the file's declared minimum and solution (exit 1 when they disagree).
//   bricklayer-study windows [--step S] PROBLEM
//       For designing problems: where the last block of the file's solution may go (the other solution
//       blocks in place), as x intervals per row on a grid of S block lengths (default 0.001).
//   bricklayer-study send start|pause|resume|repeat|abort|done [--session ID] [--lcm-url URL]
//       Publishes one study_command_t on BL_STUDY_COMMAND for the session driver.
//   bricklayer-study script [--trial1 N] [--trial2 N] [--answers A,A,A] [--trial-seconds S] [--problems DIR] OUT
//       Writes a scripted subject's whole session as a simcam scenario (for bricklayer-simcam).
//   bricklayer-study check PROBLEM PILE
//       Judges a final pile (bricklayer-predict's stack JSON, "-" for stdin) as an answer to a stabilise
//       problem; prints one JSON line {"outcome", "stands", "blocks_added", "minimum_added", "score", "reason"}.
//
// Exit status: 0 done; 1 bad input (unreadable log or problem file, a study message that does not
// decode, a problem file that says something untrue); 2 bad arguments.
#include <algorithm>
#include <cmath>
#include <fstream>
#include <iostream>
#include <sstream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "bricklayer/common/channels.h"
#include "bricklayer/common/flags.h"
#include "bricklayer/common/lcm_url.h"
#include "bricklayer/runtime/codec.h"
#include "bricklayer/runtime/lcm_bus.h"
#include "bricklayer/study/channels.h"
#include "bricklayer/study_command_t.hpp"
#include "bricklayer/study/checker.h"
#include "bricklayer/study/problem.h"
#include "bricklayer/study/study_log.h"
#include "bricklayer/study/subject_script.h"
#include "bricklayer/study/table.h"

namespace {

using bricklayer::FlagError;
namespace study = bricklayer::study;

constexpr const char* kUsage =
    "usage: bricklayer-study report [--csv FILE] [--tests-csv FILE] LOG...\n"
    "       bricklayer-study minimum PROBLEM...\n"
    "       bricklayer-study windows [--step S] PROBLEM\n"
    "       bricklayer-study check PROBLEM PILE\n"
    "       bricklayer-study send start|pause|resume|repeat|abort|done [--session ID] [--lcm-url URL]\n"
    "       bricklayer-study script [--trial1 N] [--trial2 N] [--answers A,A,A] [--trial-seconds S] [--problems DIR] OUT\n"
    "\n"
    "report   Table 1 of the seed paper's study from recorded bus logs: per condition (blue, red, proposed)\n"
    "         the subjects, trial 1 average score, how many solved problems 1-3 and how many of them used\n"
    "         excess blocks, trial 2 average score, mean and variance of trial 2 / trial 1; between\n"
    "         conditions the F-test (equal variance) and the t-test of that ratio, two-sided p-values.\n"
    "         --csv FILE        the per-condition rows as CSV (- = stdout)\n"
    "         --tests-csv FILE  the between-condition rows as CSV (- = stdout)\n"
    "minimum  the fewest added blocks that make each stabilise problem's pile stand (exact annotator),\n"
    "         with a witness and whether fewer were proven impossible; checks the file's declared values.\n"
    "windows  for problem designers: the x intervals (per row, grid --step, default 0.001) where the last\n"
    "         block of the file's solution makes the pile stand, the other solution blocks in place.\n"
    "send     one command to the running session driver (bricklayer-study-session): pause, resume,\n"
    "         repeat (the current step again; between steps the one just finished), abort, done (the\n"
    "         subject's answer to a stabilise problem), start (a driver started with --wait-for-start).\n"
    "script   a scripted subject as a simcam scenario: games to scores N (1..117), answers to problems\n"
    "         1-3 (correct, excess or failed; problem 3 correct or failed), on the problems in DIR\n"
    "         (default launch/problems: stabilise-two, stabilise-one, score-100-four);\n"
    "         timed for a session driver with the same --trial-seconds (default 120).\n"
    "check    judge PILE (stack JSON as bricklayer-predict reads it; - = stdin) as the subject's final\n"
    "         pile for PROBLEM: correct, excess or failed, as one JSON line.\n";

void write_to(const std::string& path, const std::string& text) {
  if (path == "-") {
    std::cout << text;
    return;
  }
  std::ofstream out(path);
  if (!out) throw std::runtime_error(path + ": cannot be written");
  out << text;
  if (!out.flush()) throw std::runtime_error(path + ": write failed");
}

std::string read_all(const std::string& path) {
  std::stringstream buffer;
  if (path == "-") {
    buffer << std::cin.rdbuf();
  } else {
    std::ifstream in(path);
    if (!in) throw std::runtime_error(path + ": cannot be read");
    buffer << in.rdbuf();
  }
  return buffer.str();
}

int report(const std::vector<std::string>& args) {
  std::string csv, tests_csv;
  std::vector<std::string> logs;
  for (size_t i = 0; i < args.size(); ++i) {
    const std::string& a = args[i];
    if (a == "--csv" || a == "--tests-csv") {
      if (i + 1 >= args.size()) throw FlagError(a + " needs a file name (or - for stdout)");
      (a == "--csv" ? csv : tests_csv) = args[++i];
    } else if (a.rfind("--", 0) == 0) {
      throw FlagError("report: unknown flag '" + a + "' (expected --csv FILE, --tests-csv FILE)");
    } else {
      logs.push_back(a);
    }
  }
  if (logs.empty()) throw FlagError("report: no logs given (see --help)");
  study::StudyCollector collector;
  size_t bad = 0;
  for (const std::string& path : logs) {
    const study::LogReadCounts counts = study::read_study_log(path, collector);
    bad += counts.bad_messages;
    for (const std::string& e : counts.errors) std::cerr << "bricklayer-study: " << e << "\n";
    std::cerr << "bricklayer-study: " << path << ": " << counts.events << " events, " << counts.study_messages
              << " study messages, " << counts.bad_messages << " that did not decode\n";
  }
  for (const std::string& p : collector.problems()) std::cerr << "bricklayer-study: " << p << "\n";
  const study::StudyTable table = study::make_table(collector.sessions());
  if (csv != "-" && tests_csv != "-") std::cout << study::format_table(table);
  if (!csv.empty()) write_to(csv, study::table_csv(table));
  if (!tests_csv.empty()) write_to(tests_csv, study::tests_csv(table));
  return bad == 0 ? 0 : 1;
}

int minimum(const std::vector<std::string>& args) {
  if (args.empty()) throw FlagError("minimum: no problem files given (see --help)");
  int status = 0;
  for (const std::string& path : args) {
    const study::Problem problem = study::load_problem(path);
    if (problem.kind != study::ProblemKind::kStabilise) {
      std::cout << problem.name << ": a score problem (" << problem.min_score << " points with at most "
                << problem.max_blocks << " blocks in " << problem.time_limit_ms / 1000.0 << " s); nothing to compute\n";
      continue;
    }
    study::SearchOptions options;
    options.position_tolerance = problem.position_tolerance;
    options.max_added = problem.max_added;
    const study::MinimumResult r = study::minimum_added(problem.pile, options);
    std::cout << problem.name << ": minimum " << r.summary << "; " << r.predictions << " annotator calls\n";
    for (const study::Placement& p : r.witness) std::cout << "  witness: row " << p.row << " x " << p.x << "\n";
    const bool solution_stands = study::stands(study::with_added(problem.pile, problem.solution), problem.position_tolerance);
    if (!solution_stands) {
      std::cout << "  ERROR: the file's solution does not stand\n";
      status = 1;
    }
    if (r.minimum != problem.minimum_added || !r.proven) {
      std::cout << "  ERROR: the file declares minimum_added " << problem.minimum_added << "\n";
      status = 1;
    }
  }
  return status;
}

int windows(const std::vector<std::string>& args) {
  double step = 0.001;
  std::vector<std::string> files;
  for (size_t i = 0; i < args.size(); ++i) {
    if (args[i] == "--step") {
      if (i + 1 >= args.size()) throw FlagError("--step needs a value in block lengths");
      try {
        step = std::stod(args[++i]);
      } catch (const std::exception&) {
        throw FlagError("--step must be a number of block lengths, got '" + args[i] + "'");
      }
      if (!(step >= 1e-5 && step <= 0.5)) throw FlagError("--step must be in [1e-5, 0.5]");
    } else {
      files.push_back(args[i]);
    }
  }
  if (files.size() != 1) throw FlagError("windows: expected one PROBLEM");
  const study::Problem problem = study::load_problem(files[0]);
  if (problem.kind != study::ProblemKind::kStabilise || problem.solution.empty()) {
    throw FlagError("windows: needs a stabilise problem with a solution");
  }
  std::vector<study::Placement> fixed(problem.solution.begin(), problem.solution.end() - 1);
  const bricklayer::core::Stack base = study::with_added(problem.pile, fixed);
  for (int32_t row = 0; row <= study::highest_useful_row(base); ++row) {
    for (const study::Range& range : study::placement_ranges(base, row)) {
      bool inside = false;
      double from = 0.0;
      const long n = static_cast<long>(std::ceil((range.hi - range.lo) / step));
      for (long i = 0; i <= n; ++i) {
        const double x = std::min(range.hi, range.lo + static_cast<double>(i) * step);
        bool ok = false;
        try {
          ok = study::stands(study::with_added(base, {{row, x}}), problem.position_tolerance);
        } catch (const bricklayer::core::StackError&) {
        }
        if (ok && !inside) from = x;
        if (!ok && inside) std::cout << "row " << row << ": x in [" << from << ", " << x - step << "]\n";
        inside = ok;
      }
      if (inside) std::cout << "row " << row << ": x in [" << from << ", " << range.hi << "]\n";
    }
  }
  return 0;
}

int check(const std::vector<std::string>& args) {
  if (args.size() != 2) throw FlagError("check: expected PROBLEM PILE, got " + std::to_string(args.size()) + " argument(s)");
  const study::StabiliseChecker checker(study::load_problem(args[0]));
  bricklayer::core::Stack pile;
  try {
    pile = bricklayer::core::parse_stack(read_all(args[1]));
  } catch (const bricklayer::core::StackError& e) {
    throw std::runtime_error(args[1] + ": " + e.what());
  }
  const study::Verdict v = checker.check(pile);
  nlohmann::json out{{"problem", checker.problem().name}, {"outcome", study::to_string(v.outcome)},
                     {"stands", v.stands}, {"blocks_added", v.blocks_added}, {"minimum_added", v.minimum_added},
                     {"score", v.score}, {"reason", v.reason}};
  std::cout << out.dump() << "\n";
  return 0;
}

int send(const std::vector<std::string>& args) {
  std::string session, url_flag, name;
  for (size_t i = 0; i < args.size(); ++i) {
    if (args[i] == "--session" || args[i] == "--lcm-url") {
      if (i + 1 >= args.size()) throw FlagError(args[i] + " needs a value");
      (args[i] == "--session" ? session : url_flag) = args[i + 1];
      ++i;
    } else if (args[i].rfind("--", 0) == 0) {
      throw FlagError("send: unknown flag '" + args[i] + "' (expected --session ID, --lcm-url URL)");
    } else if (name.empty()) {
      name = args[i];
    } else {
      throw FlagError("send: one command at a time");
    }
  }
  const std::vector<std::pair<std::string, int8_t>> commands{
      {"start", bricklayer::study_command_t::START},   {"pause", bricklayer::study_command_t::PAUSE},
      {"resume", bricklayer::study_command_t::RESUME}, {"repeat", bricklayer::study_command_t::REPEAT},
      {"abort", bricklayer::study_command_t::ABORT},   {"done", bricklayer::study_command_t::DONE}};
  int8_t command = 0;
  for (const auto& [n, c] : commands) {
    if (n == name) command = c;
  }
  if (command == 0) throw FlagError("send: expected start, pause, resume, repeat, abort or done, got '" + name + "'");
  const std::string url = bricklayer::resolve_lcm_url(url_flag);
  bricklayer::check_lcm_url(url);
  bricklayer::runtime::LcmBus bus(url);
  bricklayer::study_command_t msg{};
  msg.utime = bus.now_utime();
  msg.session_id = session;
  msg.command = command;
  msg.sequence = msg.utime;  // unique per send: a driver ignores only a repeat of the same message
  const std::vector<uint8_t> bytes = bricklayer::runtime::encode(msg);
  if (!bus.publish(bricklayer::channel(study::kStudyCommandChannel), bytes.data(), bytes.size())) {
    throw std::runtime_error("the bus refused the command: " + bus.problem());
  }
  return 0;
}

int script(const std::vector<std::string>& args) {
  study::SubjectScript subject;
  double trial_seconds = 120.0;
  std::string out;
  std::string problems = "launch/problems";
  auto number = [](const std::string& flag, const std::string& value) {
    try {
      size_t used = 0;
      const double v = std::stod(value, &used);
      if (used != value.size()) throw std::invalid_argument(value);
      return v;
    } catch (const std::exception&) {
      throw FlagError(flag + " must be a number, got '" + value + "'");
    }
  };
  for (size_t i = 0; i < args.size(); ++i) {
    const std::string& a = args[i];
    if (a == "--problems") {
      if (i + 1 >= args.size()) throw FlagError("--problems needs a folder");
      problems = args[++i];
    } else if (a == "--trial1" || a == "--trial2" || a == "--answers" || a == "--trial-seconds") {
      if (i + 1 >= args.size()) throw FlagError(a + " needs a value");
      const std::string v = args[++i];
      if (a == "--trial1") subject.trial1_score = static_cast<int32_t>(number(a, v));
      if (a == "--trial2") subject.trial2_score = static_cast<int32_t>(number(a, v));
      if (a == "--trial-seconds") trial_seconds = number(a, v);
      if (a == "--answers") {
        std::stringstream list(v);
        std::string item;
        size_t k = 0;
        while (std::getline(list, item, ',')) {
          if (k >= 3) throw FlagError("--answers takes three outcomes, e.g. correct,excess,failed");
          if (item == "correct") subject.answers[k] = study::Outcome::kCorrect;
          else if (item == "excess") subject.answers[k] = study::Outcome::kExcess;
          else if (item == "failed") subject.answers[k] = study::Outcome::kFailed;
          else throw FlagError("--answers: '" + item + "' is not correct, excess or failed");
          ++k;
        }
        if (k != 3) throw FlagError("--answers takes three outcomes, e.g. correct,excess,failed");
      }
    } else if (a.rfind("--", 0) == 0) {
      throw FlagError("script: unknown flag '" + a + "'");
    } else if (out.empty()) {
      out = a;
    } else {
      throw FlagError("script: one output file");
    }
  }
  if (out.empty()) throw FlagError("script: no output file given");
  if (!(trial_seconds >= 1 && trial_seconds <= 3600)) throw FlagError("--trial-seconds must be in 1..3600");
  // The script's own values first: a typo is a bad argument whatever the problem files say.
  for (int32_t score : {subject.trial1_score, subject.trial2_score}) {
    if (score < 1 || score > 117) throw FlagError("--trial1/--trial2 must be in 1..117 (a standing pile of four), got " + std::to_string(score));
  }
  if (subject.answers[2] == study::Outcome::kExcess) throw FlagError("--answers: problem 3 (score) is correct or failed, never excess");
  study::SessionSetup timing;
  timing.trial_ms = static_cast<int64_t>(trial_seconds * 1000);
  const std::string dir = problems + "/";
  std::string json;
  try {
    json = study::subject_scenario_json(subject, timing, study::load_problem(dir + "stabilise-two.json"),
                                        study::load_problem(dir + "stabilise-one.json"),
                                        study::load_problem(dir + "score-100-four.json"));
  } catch (const std::invalid_argument& e) {
    throw FlagError(e.what());
  }
  write_to(out, json + "\n");
  return 0;
}

int Main(int argc, char** argv) {
  if (argc < 2) throw FlagError("no command given\n" + std::string(kUsage));
  const std::string command = argv[1];
  std::vector<std::string> args(argv + 2, argv + argc);
  if (command == "--help" || command == "-h" || command == "help" ||
      std::find(args.begin(), args.end(), "--help") != args.end()) {
    std::cout << kUsage;
    return 0;
  }
  if (command == "report") return report(args);
  if (command == "minimum") return minimum(args);
  if (command == "check") return check(args);
  if (command == "windows") return windows(args);
  if (command == "send") return send(args);
  if (command == "script") return script(args);
  throw FlagError("unknown command '" + command + "' (expected report, minimum, windows, check, send or script)");
}

}  // namespace

int main(int argc, char** argv) { return bricklayer::run_main("bricklayer-study", Main, argc, argv); }
