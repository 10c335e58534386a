// Disk space for the bus log: the free space of the logger's folder against what the log series may
// grow to (its budget) and the minimum that must stay free.
#pragma once

#include <cstdint>
#include <optional>
#include <string>

#include "bricklayer/doctor/check.h"
#include "bricklayer/doctor/host_plan.h"

namespace bricklayer::doctor {

struct DiskBudget {
  std::string folder;                  // where the logger writes (absolute)
  std::optional<uint64_t> max_bytes;   // the most the series may hold; nullopt = unbounded (rotate 0)
  uint64_t min_free_bytes = 0;         // below this the disk is too full for the exhibit
  std::string source;                  // where the budget came from, for the report
};

// From the profile's logger entry: its budget_mb bounds the series (the logger deletes the oldest
// recordings beyond it), else rotate x split_mb (the oldest file beyond rotate files of at most split_mb
// each); the minimum free space is the larger of the caller's and the logger's min_free_mb.
DiskBudget budget_from_plan(const HostPlan& plan, uint64_t min_free_bytes);

CheckResult check_disk(const DiskBudget& budget);

}  // namespace bricklayer::doctor
