// bricklayer-overhang-table: computes the best possible overhang of n = 1..N blocks with the SLP optimiser on CLP
// (bricklayer/planner/best_overhang.h) and writes the table the score display reads
// ({"1": 0.5, "2": 0.75, ...}) plus the stacks themselves (for verification and display).
// Deterministic for a given --seed. Not a bus process.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <stdexcept>
#include <thread>

#include <nlohmann/json.hpp>

#include "bricklayer/common/flags.h"
#include "bricklayer/common/log.h"
#include "bricklayer/planner/best_overhang.h"

namespace {

using namespace bricklayer;

nlohmann::ordered_json stack_json(const planner::OverhangStack& s) {
  nlohmann::ordered_json blocks = nlohmann::ordered_json::array();
  for (const planner::PlacedBlock& b : s.blocks) blocks.push_back({{"row", b.row}, {"x", b.x}});
  return {{"overhang", s.overhang}, {"residual", s.residual}, {"blocks", blocks}};
}

planner::OverhangStack stack_from_json(const nlohmann::json& e) {
  planner::OverhangStack s;
  s.overhang = e.at("overhang").get<double>();
  s.residual = e.at("residual").get<double>();
  for (const auto& b : e.at("blocks")) s.blocks.push_back({b.at("row").get<int>(), b.at("x").get<double>()});
  return s;
}

nlohmann::json read_json(const std::string& flag, const std::string& path) {
  std::ifstream in(path);
  if (!in) throw FlagError("--" + flag + ": cannot read " + path);
  try {
    return nlohmann::json::parse(in);
  } catch (const nlohmann::json::exception& e) {
    throw FlagError("--" + flag + ": " + path + " is not JSON (" + e.what() + ")");
  }
}

// Stacks n = 1..count of a stacks file written by this program.
std::vector<planner::OverhangStack> read_stacks(const std::string& flag, const std::string& path, int64_t count) {
  const nlohmann::json old = read_json(flag, path);
  std::vector<planner::OverhangStack> out;
  for (int n = 1; n <= count; ++n) {
    const std::string key = std::to_string(n);
    if (!old.contains(key)) throw FlagError("--" + flag + ": " + path + " has no stack for n = " + key);
    out.push_back(stack_from_json(old.at(key)));
    if (out.back().blocks.size() != static_cast<size_t>(n))
      throw FlagError("--" + flag + ": " + path + ": stack " + key + " does not have " + key + " blocks");
  }
  return out;
}

// Written whole to a temporary file and renamed over path: a run killed while writing leaves the previous
// version, never half a file, so it can be continued.
void write_atomically(const std::string& path, const std::string& text) {
  const std::string tmp = path + ".tmp";
  {
    std::ofstream out(tmp, std::ios::trunc);
    out << text;
    if (!out.flush()) throw std::runtime_error("cannot write " + tmp);
  }
  if (std::rename(tmp.c_str(), path.c_str()) != 0) throw std::runtime_error("cannot rename " + tmp + " to " + path);
}

int Main(int argc, char** argv) {
  Flags flags("bricklayer-overhang-table",
              "Searches the largest overhang of n = 1..--max-n blocks (sequential linear programming over block\n"
              "positions and contact forces, beam search over layouts) and writes the table and the stacks as JSON;\n"
              "a row is written only when the exact annotator reads its stack balanced (zero position tolerance).\n"
              "After every n it also writes --checkpoint; --continue goes on from there after an interruption and\n"
              "writes the same files as a run that was never stopped.");
  const planner::OverhangSearchOptions defaults;  // the flags' defaults are the library's
  auto text = [](auto v) { return std::to_string(v); };
  flags.add("max-n", "60", "largest number of blocks");
  flags.add("beam", text(defaults.beam), "layouts kept per n");
  flags.add("alike", text(defaults.alike),
            "of layouts with the same overhang, at most this many in the beam and the restarts (0 = no limit)");
  flags.add("variety", text(defaults.variety),
            "more layouts in the beam: the best of each row of the rightmost block the beam lacks, up to this many");
  flags.add("variety-from", text(defaults.variety_from), "the n from which --variety applies");
  flags.add("perturbations", text(defaults.perturbations), "seeded restarts around the best layouts per n");
  flags.add("wall-seeds", text(defaults.wall_seeds), "seeded brick-wall start layouts per n (n >= 8)");
  flags.add("shrink", defaults.shrink ? "true" : "false",
            "after each n, try the best n stack minus each block as the n-1 stack (and on down)");
  flags.add("moves", text(defaults.moves), "local improvement: one-block moves re-optimised per n (0 = off)");
  flags.add("seed", text(defaults.seed), "random seed of the restarts");
  flags.add("table", "best_overhang.json", "output: {\"n\": overhang} in block lengths");
  flags.add("stacks", "best_overhang_stacks.json", "output: the stacks ({\"n\": [{\"row\", \"x\"}...]})");
  flags.add("checkpoint", "best_overhang_checkpoint.json", "output after every n: where the search stands (for --continue)");
  flags.add_bool("continue", "go on from --checkpoint (written by a run with the same options) instead of from n = 1");
  flags.add("tolerance", "1e-9", "largest accepted constraint residual of an optimised stack");
  flags.add("resume", "", "stacks file of an earlier run: keep its results for n = 1..--resume-n and continue");
  flags.add("resume-n", "0", "with --resume: how many of its results to keep");
  flags.add("start-layouts", "", "stacks file of an earlier run: each of its stacks is one more start layout at its n");
  flags.add("jobs", "0", "optimisations run at once, on threads (0 = one per core); the files do not depend on it");
  flags.add("log-level", "info", "debug, info, warn or error");
  if (!flags.parse(argc, argv)) return 0;
  log::set_level(log::parse_level(flags.get("log-level")));
  const int64_t max_n = flags.get_int("max-n");
  if (max_n < 1 || max_n > 60) throw FlagError("--max-n must be between 1 and 60");
  planner::OverhangSearchOptions options;
  options.beam = static_cast<int>(flags.get_int("beam"));
  options.alike = static_cast<int>(flags.get_int("alike"));
  options.variety = static_cast<int>(flags.get_int("variety"));
  options.variety_from = static_cast<int>(flags.get_int("variety-from"));
  options.perturbations = static_cast<int>(flags.get_int("perturbations"));
  options.wall_seeds = static_cast<int>(flags.get_int("wall-seeds"));
  options.moves = static_cast<int>(flags.get_int("moves"));
  options.shrink = flags.get_bool("shrink");
  options.seed = static_cast<uint64_t>(flags.get_int("seed"));
  if (options.beam < 1 || options.alike < 0 || options.variety < 0 || options.perturbations < 0 || options.wall_seeds < 0 || options.moves < 0)
    throw FlagError("--beam must be >= 1; --alike, --variety, --perturbations, --wall-seeds and --moves >= 0");
  const int64_t jobs = flags.get_int("jobs");
  if (jobs < 0 || jobs > 256) throw FlagError("--jobs must be between 0 and 256");
  options.jobs = jobs > 0 ? static_cast<int>(jobs) : static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  options.tolerance = flags.get_double("tolerance");
  if (!(options.tolerance > 0 && options.tolerance < 1e-3)) throw FlagError("--tolerance must be in (0, 1e-3)");
  if (!flags.get("resume").empty()) {
    const int64_t keep = flags.get_int("resume-n");
    if (keep < 1 || keep >= max_n) throw FlagError("--resume-n must be between 1 and --max-n - 1");
    options.resume_from = read_stacks("resume", flags.get("resume"), keep);
  }
  if (!flags.get("start-layouts").empty())
    options.start_layouts = read_stacks("start-layouts", flags.get("start-layouts"), max_n);

  // What shapes the answer (not --jobs, --max-n or the file names): a checkpoint is continued only under the
  // same, or the continued run would not be the uninterrupted one.
  nlohmann::ordered_json shaping = {{"beam", options.beam},
                                    {"alike", options.alike},
                                    {"variety", options.variety},
                                    {"variety-from", options.variety_from},
                                    {"perturbations", options.perturbations},
                                    {"wall-seeds", options.wall_seeds},
                                    {"shrink", options.shrink},
                                    {"moves", options.moves},
                                    {"seed", options.seed},
                                    {"tolerance", options.tolerance},
                                    {"resume", flags.get("resume")},
                                    {"resume-n", flags.get_int("resume-n")},
                                    {"start-layouts", flags.get("start-layouts")}};
  const std::string checkpoint_path = flags.get("checkpoint");
  if (flags.get_bool("continue")) {
    const nlohmann::json saved = read_json("checkpoint", checkpoint_path);
    if (!saved.contains("options") || saved.at("options") != nlohmann::json(shaping))
      throw FlagError("--continue: " + checkpoint_path + " was written with other options (" +
                      (saved.contains("options") ? saved.at("options").dump() : std::string("none")) + ", now " +
                      shaping.dump() + "); give the same ones");
    planner::OverhangSearchState state;
    try {
      state.first_new = saved.at("first_new").get<int>();
      state.rng = saved.at("rng").get<std::string>();
      for (const auto& s : saved.at("stacks")) state.best_per_n.push_back(stack_from_json(s));
      for (const auto& s : saved.at("beam")) state.beam.push_back(stack_from_json(s));
    } catch (const nlohmann::json::exception& e) {
      throw FlagError("--continue: " + checkpoint_path + " is not a checkpoint of this program (" + e.what() + ")");
    }
    if (static_cast<int64_t>(state.best_per_n.size()) >= max_n)
      throw FlagError("--continue: " + checkpoint_path + " already reaches n = " + std::to_string(state.best_per_n.size()) +
                      "; give a larger --max-n");
    log::info("continuing from ", checkpoint_path, " after n = ", state.best_per_n.size());
    options.resume_from.clear();
    options.continue_from = std::move(state);
  }

  nlohmann::ordered_json table = nlohmann::ordered_json::object();
  nlohmann::ordered_json stacks = nlohmann::ordered_json::object();
  auto write = [&] {
    write_atomically(flags.get("table"), table.dump(1) + "\n");
    write_atomically(flags.get("stacks"), stacks.dump(1) + "\n");
  };
  const auto started = std::chrono::steady_clock::now();
  auto last = started;
  planner::search_best_overhang(
      static_cast<int>(max_n), options,
      [&](int n, const planner::OverhangStack& s) {
        if (stacks.contains(std::to_string(n)))
          log::info("n=", n, " improved by a larger stack minus a block: overhang ", s.overhang);
        table[std::to_string(n)] = std::round(s.overhang * 1e6) / 1e6;
        stacks[std::to_string(n)] = stack_json(s);
      },
      [&](const planner::OverhangSearchState& state) {
        // Files first, then the checkpoint: a checkpoint never runs ahead of the files it continues.
        write();
        nlohmann::ordered_json saved = {{"options", shaping}, {"first_new", state.first_new}, {"rng", state.rng}};
        saved["stacks"] = nlohmann::ordered_json::array();
        for (const auto& s : state.best_per_n) saved["stacks"].push_back(stack_json(s));
        saved["beam"] = nlohmann::ordered_json::array();
        for (const auto& s : state.beam) saved["beam"].push_back(stack_json(s));
        write_atomically(checkpoint_path, saved.dump() + "\n");
        // Progress: wall time is for the reader only, never for the search.
        const auto now = std::chrono::steady_clock::now();
        const planner::OverhangStack& s = state.best_per_n.back();
        log::info("n=", state.best_per_n.size(), " overhang ", s.overhang, " residual ", s.residual, " (",
                  std::chrono::duration_cast<std::chrono::seconds>(now - last).count(), " s, ",
                  std::chrono::duration_cast<std::chrono::seconds>(now - started).count(), " s in all)");
        last = now;
      });
  write();
  return 0;
}

}  // namespace

int main(int argc, char** argv) { return bricklayer::run_main("bricklayer-overhang-table", &Main, argc, argv); }
