// Reads the events of one or more standard LCM log files in order, and says where a file is damaged.
// lcm::LogFile cannot tell a truncated file from its end, and silently skips damaged bytes; the
// exporters must report both, so they read through this one class (a thin reader of LCM's documented
// event format: sync word 0xEDA1DA01, event number, timestamp, channel length, data length, channel,
// data; all big-endian).
#pragma once

#include <cstdint>
#include <cstdio>
#include <stdexcept>
#include <string>
#include <vector>

namespace bricklayer::inspect {

class LogOpenError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct LogEvent {
  int64_t number = 0;        // the logger's event number
  int64_t timestamp_us = 0;  // the logger's receive time, microseconds since the epoch
  std::string channel;
  std::vector<uint8_t> data;
  size_t file_index = 0;     // which of the files
  uint64_t offset = 0;       // byte offset of the event in that file
};

// A damaged part of a file: a torn event at the end (truncated) or bytes that are no event (corrupt).
struct LogProblem {
  std::string file;
  uint64_t offset = 0;
  bool truncated = false;    // the file ends inside an event
  std::string what;          // one line for the operator
};

class LogSource {
 public:
  // Opens every file now (throws LogOpenError naming the one that cannot be read).
  explicit LogSource(std::vector<std::string> files);
  ~LogSource();
  LogSource(const LogSource&) = delete;
  LogSource& operator=(const LogSource&) = delete;

  // The next event of all files in order; false when every file is read. After a corrupt stretch the
  // reader continues at the next sync word (as LCM does), after a torn event with the next file;
  // both are recorded in problems().
  bool next(LogEvent& event);

  uint64_t bytes_read() const { return done_bytes_ + position_; }
  uint64_t total_bytes() const { return total_bytes_; }
  const std::vector<std::string>& files() const { return files_; }
  const std::vector<LogProblem>& problems() const { return problems_; }

 private:
  bool open_next();
  bool read_exact(void* out, size_t n);
  bool resync(uint64_t from);
  void problem(uint64_t offset, bool truncated, std::string what);

  std::vector<std::string> files_;
  std::vector<uint64_t> sizes_;
  uint64_t total_bytes_ = 0;
  uint64_t done_bytes_ = 0;
  size_t current_ = 0;
  bool opened_ = false;
  std::FILE* file_ = nullptr;
  uint64_t position_ = 0;
  std::vector<LogProblem> problems_;
};

}  // namespace bricklayer::inspect
