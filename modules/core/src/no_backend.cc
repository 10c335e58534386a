// Stubs for backends that were not compiled in: they exist, say so, and never break the build.
#include "bricklayer/core/program.h"

namespace bricklayer::core::opt {
namespace {

class MissingSolver final : public Solver {
 public:
  explicit MissingSolver(std::string name) : name_(std::move(name)) {}
  std::string name() const override { return name_; }
  bool available() const override { return false; }
  bool supports_quadratic() const override { return false; }

 protected:
  SolveResult do_solve(const Problem&, const SolverOptions&) const override { return {}; }

 private:
  std::string name_;
};

}  // namespace

#ifndef BRICKLAYER_HAVE_CLP
std::unique_ptr<Solver> make_clp_solver() { return std::make_unique<MissingSolver>("clp"); }
#endif
#ifndef BRICKLAYER_HAVE_NLOPT
std::unique_ptr<Solver> make_nlopt_solver() { return std::make_unique<MissingSolver>("nlopt"); }
#endif

}  // namespace bricklayer::core::opt
