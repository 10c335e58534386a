#include "bricklayer/runtime/node_main.h"

namespace bricklayer::runtime::node_main_detail {

void declare_runtime_flags(Flags& flags) {
  flags.add("lcm-url", "", "LCM URL (default: LCM_DEFAULT_URL, else host-only udpm ttl=0)");
  flags.add("log-level", "info", "debug, info, warn or error");
  flags.add_bool("check-config", "check the flags and every file they name, print the configuration, start nothing");
  flags.add_bool("describe-config", "print the configuration's declaration (names, defaults, rules) as JSON");
}

std::string apply_runtime_flags(const Flags& flags) {
  try {
    log::set_level(log::parse_level(flags.get("log-level")));
  } catch (const std::invalid_argument&) {
    throw FlagError("--log-level must be debug, info, warn or error, got '" + flags.get("log-level") + "'");
  }
  const std::string url = resolve_lcm_url(flags.get("lcm-url"));
  try {
    check_lcm_url(url);
  } catch (const std::invalid_argument& e) {
    throw FlagError(e.what());
  }
  return url;
}

int report_check(const std::string& program, const nlohmann::json& config, const std::vector<std::string>& missing) {
  for (const std::string& m : missing) std::cerr << program << ": error: " << m << "\n";
  std::cout << (missing.empty() ? "ok " : "missing files ") << config.dump() << std::endl;
  return missing.empty() ? 0 : 2;
}

}  // namespace bricklayer::runtime::node_main_detail
