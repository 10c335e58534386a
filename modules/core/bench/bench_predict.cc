// bricklayer-bench-predict: median and p99 latency and peak heap of predict() for each annotator x backend on
// piles built as a player would (piles::player_pile, fixed seeds), at several pile sizes.
// Usage: bricklayer-bench-predict [--sizes 10,25,...] [--piles N] [--max-nlopt-blocks N] [--quick]
#include <malloc.h>
#include <time.h>
#include <sys/resource.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <new>
#include <sstream>
#include <string>
#include <vector>

#include "bricklayer/core/contacts.h"
#include "bricklayer/core/dynamics.h"
#include "bricklayer/piles/player_pile.h"
#include "bricklayer/core/knife_edge.h"
#include "bricklayer/core/predict.h"

// Heap accounting through operator new (CLP and Eigen allocate through it; NLopt's C core uses malloc and
// is only seen in the process peak RSS).
namespace {
std::atomic<size_t> g_current{0};
std::atomic<size_t> g_peak{0};
}  // namespace

void* operator new(size_t size) {
  void* p = std::malloc(size ? size : 1);
  if (!p) throw std::bad_alloc();
  const size_t now = g_current.fetch_add(malloc_usable_size(p)) + malloc_usable_size(p);
  size_t peak = g_peak.load();
  while (now > peak && !g_peak.compare_exchange_weak(peak, now)) {
  }
  return p;
}
void operator delete(void* p) noexcept {
  if (!p) return;
  g_current.fetch_sub(malloc_usable_size(p));
  std::free(p);
}
void operator delete(void* p, size_t) noexcept { operator delete(p); }
void* operator new[](size_t size) { return operator new(size); }
void operator delete[](void* p) noexcept { operator delete(p); }
void operator delete[](void* p, size_t) noexcept { operator delete(p); }

namespace {

using namespace bricklayer::core;
using bricklayer::piles::player_pile;

struct Config {
  Annotator annotator;
  std::string solver;
  QpMethod qp;
  bool lp_first;
  std::string label;
  double uncertainty = -1.0;  // >= 0: judge_knife_edge with this half-width for every block (margin included)
};

// CPU time of this thread: unlike wall time it does not count the time other processes take the core
// (the machine is shared; under load the wall-clock p99 measures the scheduler, not this code).
double thread_cpu_ms() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) * 1e3 + static_cast<double>(ts.tv_nsec) * 1e-6;
}

double percentile(std::vector<double> v, double q) {
  std::sort(v.begin(), v.end());
  const size_t k = std::min(v.size() - 1, static_cast<size_t>(std::ceil(q * static_cast<double>(v.size()))) - (q > 0 ? 1 : 0));
  return v[k];
}

std::vector<int> parse_sizes(const std::string& text) {
  std::vector<int> out;
  std::stringstream in(text);
  std::string item;
  while (std::getline(in, item, ',')) out.push_back(std::stoi(item));
  return out;
}

}  // namespace

int main(int argc, char** argv) {
  std::vector<int> sizes{10, 25, 50, 60, 100, 200, 500, 1000};
  int piles = 200;
  int max_nlopt = 100;
  int repeat = 1;
  std::string only;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto value = [&]() -> std::string {
      if (i + 1 >= argc) {
        std::fprintf(stderr, "bricklayer-bench-predict: error: %s needs a value\n", a.c_str());
        std::exit(2);
      }
      return argv[++i];
    };
    if (a == "--sizes") sizes = parse_sizes(value());
    else if (a == "--piles") piles = std::stoi(value());
    else if (a == "--max-nlopt-blocks") max_nlopt = std::stoi(value());
    else if (a == "--only") only = value();
    else if (a == "--repeat") repeat = std::max(1, std::stoi(value()));
    else if (a == "--dump") {
      // Prints one generated pile in bricklayer-predict's input format: --dump BLOCKS SEED
      const int blocks = std::stoi(value());
      const uint64_t seed = std::stoull(value());
      const Stack s = player_pile(blocks, seed);
      std::printf("{\"block_length\": 1.0, \"block_height\": %.17g, \"table_edge\": 0.0, \"blocks\": [", s.block_height);
      for (size_t b = 0; b < s.blocks.size(); ++b) {
        std::printf("%s{\"id\": %lld, \"row\": %d, \"x\": %.17g}", b ? ", " : "", static_cast<long long>(s.blocks[b].id),
                    s.blocks[b].row, s.blocks[b].x);
      }
      std::printf("]}\n");
      return 0;
    }
    else if (a == "--help") {
      std::printf("bricklayer-bench-predict [--sizes 10,25,50,60,100,200,500,1000] [--piles 200] "
                  "[--max-nlopt-blocks 100] [--only LABEL-SUBSTRING|qp] [--repeat N]\n"
                  "--repeat N: time each pile N times and keep the fastest (filters preemption on a shared machine)\n");
      return 0;
    } else {
      std::fprintf(stderr, "bricklayer-bench-predict: error: unknown argument %s\n", a.c_str());
      return 2;
    }
  }
  const std::vector<Config> configs{
      {Annotator::kExact, "clp", QpMethod::kNnls, false, "exact nnls"},
      {Annotator::kExact, "clp", QpMethod::kNnls, false, "knife-edge u=0.003", 0.003},
      {Annotator::kExact, "clp", QpMethod::kNnls, false, "knife-edge u=0.005", 0.005},
      {Annotator::kExact, "clp", QpMethod::kNlopt, false, "exact nlopt-qp"},
      {Annotator::kExact, "clp", QpMethod::kNnls, true, "exact clp-first+nnls"},
      {Annotator::kExact, "nlopt", QpMethod::kNnls, true, "exact nlopt-first+nnls"},
      {Annotator::kPaper, "clp", QpMethod::kNnls, false, "paper clp"},
      {Annotator::kPaper, "nlopt", QpMethod::kNnls, false, "paper nlopt"},
      {Annotator::kBalance, "clp", QpMethod::kNnls, false, "balance clp"},
      {Annotator::kBalance, "nlopt", QpMethod::kNnls, false, "balance nlopt"},
  };
  std::printf("%-24s %6s %7s %10s %10s %10s %10s %10s %12s\n", "annotator/backend", "blocks", "unbal%", "median_ms",
              "p99_ms", "max_ms", "cpu_med", "cpu_p99", "peak_heap_kB");
  for (int n : sizes) {
    std::vector<Stack> stacks;
    for (int s = 0; s < piles; ++s) stacks.push_back(player_pile(n, 1000 * static_cast<uint64_t>(n) + static_cast<uint64_t>(s)));
    for (const Config& c : configs) {
      if (!only.empty() && (only == "qp" || c.label.find(only) == std::string::npos)) continue;
      const bool uses_nlopt = c.solver == "nlopt" || c.qp == QpMethod::kNlopt;
      if (uses_nlopt && n > max_nlopt) {
        std::printf("%-24s %6d   skipped (NLopt SLSQP is cubic; raise --max-nlopt-blocks)\n", c.label.c_str(), n);
        continue;
      }
      PredictOptions options;
      options.annotator = c.annotator;
      options.solver = c.solver;
      options.qp = c.qp;
      options.lp_first = c.lp_first;
      const int count = uses_nlopt ? std::min(piles, 20) : piles;
      std::vector<double> ms;
      std::vector<double> cpu;
      int unbalanced = 0;
      int knife = 0;
      int max_lps = 0;
      int failures = 0;
      size_t peak = 0;
      for (int k = 0; k < count; ++k) {
        double best_cpu = 1e300;
        double best_ms = 1e300;
        bool is_balanced = true;
        for (int rep = 0; rep < repeat; ++rep) {
          const size_t base = g_current.load();
          g_peak.store(base);
          const double c0 = thread_cpu_ms();
          const auto t0 = std::chrono::steady_clock::now();
          try {
            const Stack& pile = stacks[static_cast<size_t>(k)];
            if (c.uncertainty >= 0.0) {
              const KnifeEdgeVerdict v = judge_knife_edge(pile, std::vector<double>(pile.blocks.size(), c.uncertainty), options);
              is_balanced = v.nominal.balanced;
              if (rep == 0) {
                knife += v.certainty == Certainty::kKnifeEdge ? 1 : 0;
                max_lps = std::max(max_lps, v.linear_programs);
              }
            } else {
              is_balanced = predict(pile, options).balanced;
            }
          } catch (const std::exception& e) {
            ++failures;
            if (failures == 1) std::fprintf(stderr, "%s n=%d pile %d: %s\n", c.label.c_str(), n, k, e.what());
          }
          const auto t1 = std::chrono::steady_clock::now();
          best_cpu = std::min(best_cpu, thread_cpu_ms() - c0);
          best_ms = std::min(best_ms, std::chrono::duration<double, std::milli>(t1 - t0).count());
          peak = std::max(peak, g_peak.load() - base);
        }
        cpu.push_back(best_cpu);
        ms.push_back(best_ms);
        unbalanced += is_balanced ? 0 : 1;
      }
      std::printf("%-24s %6d %6.0f%% %10.4f %10.4f %10.4f %10.4f %10.4f %12.1f%s\n", c.label.c_str(), n,
                  100.0 * unbalanced / count, percentile(ms, 0.5), percentile(ms, 0.99),
                  *std::max_element(ms.begin(), ms.end()), percentile(cpu, 0.5), percentile(cpu, 0.99), peak / 1024.0,
                  failures ? ("  FAILED " + std::to_string(failures)).c_str() : "");
      if (c.uncertainty >= 0.0) {
        std::printf("%-24s %6d   knife edges %.0f%%, at most %d LPs per pile\n", "", n, 100.0 * knife / count, max_lps);
      }
      std::fflush(stdout);
    }
  }
  // The exact annotator's QP alone (whole pile, certificate off), on the piles the certificate cannot prove
  // balanced: the measurement behind the choice between NNLS and NLopt SLSQP.
  if (only.empty() || only == "qp") {
    std::printf("\nQP alone (whole pile, no certificate), piles the certificate does not prove balanced\n");
    std::printf("%-22s %6s %9s %10s %10s %10s\n", "qp", "blocks", "piles", "median_ms", "p99_ms", "max_ms");
    for (int n : sizes) {
      std::vector<ContactGraph> graphs;
      for (int s = 0; s < piles && graphs.size() < 40; ++s) {
        ContactGraph g = build_contacts(player_pile(n, 1000 * static_cast<uint64_t>(n) + static_cast<uint64_t>(s)));
        if (!two_point_certificate(g)) graphs.push_back(std::move(g));
      }
      if (graphs.empty()) continue;
      for (QpMethod method : {QpMethod::kNnls, QpMethod::kNlopt}) {
        if (method == QpMethod::kNlopt && n > max_nlopt) {
          std::printf("%-22s %6d   skipped\n", "nlopt slsqp", n);
          continue;
        }
        std::vector<double> ms;
        const size_t count = method == QpMethod::kNlopt ? std::min<size_t>(graphs.size(), 10) : graphs.size();
        for (size_t k = 0; k < count; ++k) {
          const auto t0 = std::chrono::steady_clock::now();
          (void)initial_accelerations(graphs[k], {}, method, false);
          const auto t1 = std::chrono::steady_clock::now();
          ms.push_back(std::chrono::duration<double, std::milli>(t1 - t0).count());
        }
        std::printf("%-22s %6d %9zu %10.4f %10.4f %10.4f\n", method == QpMethod::kNnls ? "nnls (lawson-hanson)" : "nlopt slsqp", n,
                    count, percentile(ms, 0.5), percentile(ms, 0.99), *std::max_element(ms.begin(), ms.end()));
        std::fflush(stdout);
      }
    }
  }
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  std::printf("process peak RSS: %ld kB\n", usage.ru_maxrss);
  return 0;
}
