// One finding of bricklayer-doctor: a check's name, ok / warning / failed, what it found and how to
// fix it, printed as one line. Failed means the exhibit would not run (the doctor exits 1); a warning
// means it runs worse than it should (lost frames, no beep, drifting colours).
#pragma once

#include <string>
#include <vector>

namespace bricklayer::doctor {

enum class Severity { kOk, kWarning, kFailed };

struct CheckResult {
  std::string name;    // "multicast route"
  Severity severity = Severity::kOk;
  std::string detail;  // what was found, with the figures
  std::string fix;     // a command or step; empty when ok

  static CheckResult ok(std::string name, std::string detail) { return {std::move(name), Severity::kOk, std::move(detail), ""}; }
  static CheckResult warning(std::string name, std::string detail, std::string fix) {
    return {std::move(name), Severity::kWarning, std::move(detail), std::move(fix)};
  }
  static CheckResult failed(std::string name, std::string detail, std::string fix) {
    return {std::move(name), Severity::kFailed, std::move(detail), std::move(fix)};
  }
};

const char* severity_name(Severity s);  // "ok", "warning", "FAILED"
// "warning  receive buffers     net.core.rmem_max is 212992 ... -- fix: sudo sysctl ..."
std::string format_line(const CheckResult& r);
// "10 ok, 2 warnings, 1 failed"
std::string summary(const std::vector<CheckResult>& results);
// 1 when any check failed, else 0.
int exit_code(const std::vector<CheckResult>& results);

}  // namespace bricklayer::doctor
