// The logger's disk side: a thread that writes received events to standard LCM log files (readable by
// lcm-logplayer, lcm::LogFile and bricklayer-replay), splits and rotates them, and flushes on a fixed
// period. The receiving thread only copies a message into a queue bounded in bytes, so a slow disk
// never stalls LCM's receive path; when the queue is full the event is dropped and counted (the
// overflow policy of lcm-logger's --max-unwritten-mb).
#pragma once

#include <lcm/lcm-cpp.hpp>

#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <functional>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "bricklayer/logger/log_series.h"

namespace bricklayer::logger {

struct Event {
  int64_t utime = 0;  // receive time, microseconds since the epoch (as lcm-logger records it)
  std::string channel;
  std::vector<uint8_t> data;
};

struct WriterOptions {
  std::string base;                            // file name without the .N / .NN suffix
  int rotate = 0;                              // see LogSeries
  int64_t split_bytes = 0;                     // start a new file before one would exceed this; 0 = never
  int flush_ms = 100;                          // fflush period; 0 = after every batch
  int64_t max_unwritten_bytes = 256ll << 20;   // queue bound; beyond it events are dropped (counted)
};

struct WriterStats {
  int64_t written = 0;        // events in the files
  int64_t bytes = 0;          // bytes in the files, over all files of this run
  int64_t dropped = 0;        // events refused because the queue was full
  int64_t write_errors = 0;   // events the file refused (disk full, I/O error)
  int64_t files = 0;          // files opened by this run
  int64_t queued_bytes = 0;   // now waiting in the queue
  int64_t peak_queued_bytes = 0;
  std::string current_file;
};

class EventWriter {
 public:
  // Opens the first file (throws std::runtime_error naming the path when it cannot) and starts the
  // writer thread. on_written(event) runs on the writer thread after each event is written.
  explicit EventWriter(WriterOptions options, std::function<void(const Event&)> on_written = {});
  ~EventWriter();  // stop()
  EventWriter(const EventWriter&) = delete;
  EventWriter& operator=(const EventWriter&) = delete;

  // Queues an event; false (and counted) when the queue is over its byte bound. Any thread.
  bool push(Event event);
  // The next event goes into a new file (SIGHUP, as lcm-logger).
  void request_new_file();
  // Writes everything queued, flushes, syncs to disk and closes. Idempotent.
  void stop();

  WriterStats stats() const;

  // Bytes an event takes in an LCM log file (sync word, event number, timestamp, two lengths, channel, data).
  static int64_t file_size_of(const Event& e) { return 28 + static_cast<int64_t>(e.channel.size() + e.data.size()); }

 private:
  void run();
  void open_next();  // writer thread (or constructor) only
  void close_current();
  void write(const Event& e);

  WriterOptions options_;
  std::function<void(const Event&)> on_written_;
  LogSeries series_;

  mutable std::mutex mutex_;
  std::condition_variable wake_;
  std::deque<Event> queue_;     // guarded by mutex_
  int64_t queued_bytes_ = 0;    // guarded by mutex_
  bool stopping_ = false;       // guarded by mutex_
  bool new_file_requested_ = false;  // guarded by mutex_
  WriterStats stats_;           // guarded by mutex_ (copied out by stats())

  // Writer thread only.
  std::unique_ptr<lcm::LogFile> file_;
  int64_t file_bytes_ = 0;
  std::thread thread_;
};

}  // namespace bricklayer::logger
