// Reads the events of one or more standard LCM log files in order, and says where a file is damaged:
// the runtime's LogReader (bricklayer/runtime/log_file.h) reads each file without trusting its bytes
// and reports every region that held no intact event; this class chains the files of a split log or a
// day, keeps count of the bytes for progress, and turns the regions into problems for the operator.
#pragma once

#include <cstdint>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

namespace bricklayer::runtime {
class LogReader;
}

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

  // The next event of all files in order; false when every file is read. A damaged region is skipped
  // (reading goes on at the next intact event) and recorded in problems().
  bool next(LogEvent& event);

  uint64_t bytes_read() const { return done_bytes_ + position_; }
  uint64_t total_bytes() const { return total_bytes_; }
  const std::vector<std::string>& files() const { return files_; }
  const std::vector<LogProblem>& problems() const { return problems_; }

 private:
  void take_damage();

  std::vector<std::string> files_;
  std::vector<uint64_t> sizes_;
  uint64_t total_bytes_ = 0;
  uint64_t done_bytes_ = 0;
  uint64_t position_ = 0;
  size_t current_ = 0;
  size_t damage_seen_ = 0;
  std::unique_ptr<runtime::LogReader> reader_;
  std::vector<LogProblem> problems_;
};

}  // namespace bricklayer::inspect
