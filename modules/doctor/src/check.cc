#include "bricklayer/doctor/check.h"

#include <cstdio>

namespace bricklayer::doctor {

const char* severity_name(Severity s) {
  switch (s) {
    case Severity::kOk: return "ok";
    case Severity::kWarning: return "warning";
    case Severity::kFailed: return "FAILED";
  }
  return "?";
}

std::string format_line(const CheckResult& r) {
  char head[64];
  std::snprintf(head, sizeof(head), "%-8s %-20s ", severity_name(r.severity), r.name.c_str());
  std::string line = head + r.detail;
  if (!r.fix.empty()) line += " -- fix: " + r.fix;
  return line;
}

std::string summary(const std::vector<CheckResult>& results) {
  int counts[3] = {0, 0, 0};
  for (const auto& r : results) ++counts[static_cast<int>(r.severity)];
  return std::to_string(counts[0]) + " ok, " + std::to_string(counts[1]) + (counts[1] == 1 ? " warning, " : " warnings, ") +
         std::to_string(counts[2]) + " failed";
}

int exit_code(const std::vector<CheckResult>& results) {
  for (const auto& r : results)
    if (r.severity == Severity::kFailed) return 1;
  return 0;
}

}  // namespace bricklayer::doctor
