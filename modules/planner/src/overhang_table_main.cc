// bricklayer-overhang-table: computes the best possible overhang of n = 1..N blocks with the SLP optimiser on CLP
// (bricklayer/planner/best_overhang.h) and writes the table the score display reads
// ({"1": 0.5, "2": 0.75, ...}) plus the stacks themselves (for verification and display).
// Deterministic for a given --seed. Not a bus process.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <thread>

#include <nlohmann/json.hpp>

#include "bricklayer/common/flags.h"
#include "bricklayer/common/log.h"
#include "bricklayer/planner/best_overhang.h"

namespace {

using namespace bricklayer;

int Main(int argc, char** argv) {
  Flags flags("bricklayer-overhang-table",
              "Searches the largest overhang of n = 1..--max-n blocks (sequential linear programming over block\n"
              "positions and contact forces, beam search over layouts) and writes the table and the stacks as JSON.");
  flags.add("max-n", "30", "largest number of blocks");
  flags.add("beam", "8", "layouts kept per n");
  flags.add("perturbations", "4", "seeded restarts around the best layouts per n");
  flags.add("wall-seeds", "6", "seeded brick-wall start layouts per n (n >= 8)");
  flags.add("shrink", "true", "after each n, try the best n stack minus each block as the n-1 stack (and on down)");
  flags.add("moves", "0", "local improvement: one-block moves re-optimised per n (0 = off)");
  flags.add("seed", "1", "random seed of the restarts");
  flags.add("table", "best_overhang.json", "output: {\"n\": overhang} in block lengths");
  flags.add("stacks", "best_overhang_stacks.json", "output: the stacks ({\"n\": [{\"row\", \"x\"}...]})");
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
  options.perturbations = static_cast<int>(flags.get_int("perturbations"));
  options.wall_seeds = static_cast<int>(flags.get_int("wall-seeds"));
  options.moves = static_cast<int>(flags.get_int("moves"));
  options.shrink = flags.get_bool("shrink");
  options.seed = static_cast<uint64_t>(flags.get_int("seed"));
  if (options.beam < 1 || options.perturbations < 0 || options.wall_seeds < 0 || options.moves < 0)
    throw FlagError("--beam must be >= 1; --perturbations, --wall-seeds and --moves >= 0");
  const int64_t jobs = flags.get_int("jobs");
  if (jobs < 0 || jobs > 256) throw FlagError("--jobs must be between 0 and 256");
  options.jobs = jobs > 0 ? static_cast<int>(jobs) : static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  options.tolerance = flags.get_double("tolerance");
  if (!(options.tolerance > 0 && options.tolerance < 1e-3)) throw FlagError("--tolerance must be in (0, 1e-3)");
  // Stacks n = 1..count of a stacks file written by this program.
  auto read_stacks = [](const std::string& flag, const std::string& path, int64_t count) {
    std::ifstream in(path);
    if (!in) throw FlagError("--" + flag + ": cannot read " + path);
    const nlohmann::json old = nlohmann::json::parse(in);
    std::vector<planner::OverhangStack> out;
    for (int n = 1; n <= count; ++n) {
      const std::string key = std::to_string(n);
      if (!old.contains(key)) throw FlagError("--" + flag + ": " + path + " has no stack for n = " + key);
      const auto& e = old.at(key);
      planner::OverhangStack s;
      s.overhang = e.at("overhang").get<double>();
      s.residual = e.at("residual").get<double>();
      for (const auto& b : e.at("blocks")) s.blocks.push_back({b.at("row").get<int>(), b.at("x").get<double>()});
      if (s.blocks.size() != static_cast<size_t>(n))
        throw FlagError("--" + flag + ": " + path + ": stack " + key + " does not have " + key + " blocks");
      out.push_back(std::move(s));
    }
    return out;
  };
  if (!flags.get("resume").empty()) {
    const int64_t keep = flags.get_int("resume-n");
    if (keep < 1 || keep >= max_n) throw FlagError("--resume-n must be between 1 and --max-n - 1");
    options.resume_from = read_stacks("resume", flags.get("resume"), keep);
  }
  if (!flags.get("start-layouts").empty())
    options.start_layouts = read_stacks("start-layouts", flags.get("start-layouts"), max_n);

  nlohmann::ordered_json table = nlohmann::ordered_json::object();
  nlohmann::ordered_json stacks = nlohmann::ordered_json::object();
  auto write = [&] {
    std::ofstream(flags.get("table")) << table.dump(1) << "\n";
    std::ofstream(flags.get("stacks")) << stacks.dump(1) << "\n";
  };
  planner::search_best_overhang(static_cast<int>(max_n), options, [&](int n, const planner::OverhangStack& s) {
    const double rounded = std::round(s.overhang * 1e6) / 1e6;
    table[std::to_string(n)] = rounded;
    nlohmann::ordered_json blocks = nlohmann::ordered_json::array();
    for (const planner::PlacedBlock& b : s.blocks) blocks.push_back({{"row", b.row}, {"x", b.x}});
    stacks[std::to_string(n)] = {{"overhang", s.overhang}, {"residual", s.residual}, {"blocks", blocks}};
    log::info("n=", n, " overhang ", s.overhang, " residual ", s.residual);
    write();  // keep partial results of long runs
  });
  write();
  return 0;
}

}  // namespace

int main(int argc, char** argv) { return bricklayer::run_main("bricklayer-overhang-table", &Main, argc, argv); }
