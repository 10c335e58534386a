#include "bricklayer/inspect/lcm_schema.h"

#include <utility>
#include <vector>

namespace bricklayer::inspect {

const std::vector<std::pair<std::string, std::string>>& embedded_lcm_files();  // generated

const LcmTypeSet& builtin_types() {
  static const LcmTypeSet types = [] {
    LcmTypeSet set;
    for (const auto& [name, text] : embedded_lcm_files())
      for (auto& s : parse_lcm(text, "lcmtypes/" + name)) set.add(std::move(s));
    set.finish();
    return set;
  }();
  return types;
}

}  // namespace bricklayer::inspect
