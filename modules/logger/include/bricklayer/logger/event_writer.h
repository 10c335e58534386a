// The logger's disk side: a thread that writes received events to standard LCM log files (readable by
// lcm-logplayer, lcm::LogFile and bricklayer-replay), splits and rotates them, keeps the series within
// its disk budget, maintains the recording's index, and flushes on a fixed period. The receiving
// thread only copies a message into a queue bounded in bytes, so a slow disk never stalls LCM's
// receive path; when the queue is full the event is dropped and counted (the overflow policy of
// lcm-logger's --max-unwritten-mb).
//
// What is counted as written is what reached the file: writes are checked (part_file.h), a torn event
// is cut off, and after a write error the next event goes into a new file. When the disk (or the
// budget) has no room even after deleting the oldest recordings, events are not kept, counted (lost)
// and noted in the index; the logger keeps running and writes again as soon as there is room.
#pragma once

#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "bricklayer/logger/disk_budget.h"
#include "bricklayer/logger/log_series.h"
#include "bricklayer/logger/part_file.h"
#include "bricklayer/logger/recording_index.h"

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
  int flush_ms = 100;                          // write period; 0 = after every batch
  int64_t max_unwritten_bytes = 256ll << 20;   // queue bound; beyond it events are dropped (counted)
  int64_t budget_bytes = 0;                    // the series on the disk at most; 0 = no limit
  int64_t min_free_bytes = 0;                  // free space to leave on the file system; 0 = none
  std::string series_prefix;                   // file names of the series; "" = this recording only
  bool index = true;                           // BASE.index (only without rotation: rotation renames parts)
};

struct WriterStats {
  int64_t written = 0;        // events in the files (checked writes)
  int64_t bytes = 0;          // bytes of those events, over all files of this run
  int64_t dropped = 0;        // events refused because the queue was full
  int64_t lost = 0;           // events received but not kept: no room on the disk or in the budget, I/O errors
  int64_t write_errors = 0;   // writes the file refused (each loses the events of one batch at most)
  int64_t files = 0;          // files opened by this run
  int64_t queued_bytes = 0;   // now waiting in the queue
  int64_t peak_queued_bytes = 0;
  int64_t deleted_files = 0;  // old recordings' files deleted to stay within the budget
  int64_t deleted_bytes = 0;
  int64_t series_bytes = 0;   // the series on the disk now
  int64_t free_bytes = -1;    // on the file system now (-1 unknown)
  int64_t moments = 0;        // moments noted in the index
  std::string current_file;   // "" while no file is open (after a write error, until there is room)
  std::string index_file;
  std::string last_error;
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
  // Notes a moment in the recording's index. Any thread.
  void note(Moment moment);
  // The next event goes into a new file (SIGHUP, as lcm-logger).
  void request_new_file();
  // Writes everything queued, syncs to disk and closes. Idempotent.
  void stop();

  WriterStats stats() const;

  // Bytes an event takes in an LCM log file (sync word, event number, timestamp, two lengths, channel, data).
  static int64_t file_size_of(const Event& e) { return 28 + static_cast<int64_t>(e.channel.size() + e.data.size()); }

 private:
  void run();
  bool open_next(int64_t first_utime);  // writer thread (or constructor) only; false when it cannot
  void close_current();
  void write(const std::deque<Event>& batch);
  void commit();  // writes what pending_ holds into the open file
  void lose(size_t count, int64_t from, int64_t to, const std::string& reason);
  void note_losses();
  void update_disk_stats();

  WriterOptions options_;
  std::function<void(const Event&)> on_written_;
  LogSeries series_;

  mutable std::mutex mutex_;
  std::condition_variable wake_;
  std::deque<Event> queue_;     // guarded by mutex_
  std::deque<Moment> notes_;    // guarded by mutex_
  int64_t queued_bytes_ = 0;    // guarded by mutex_
  bool stopping_ = false;       // guarded by mutex_
  bool new_file_requested_ = false;  // guarded by mutex_
  WriterStats stats_;           // guarded by mutex_ (copied out by stats())

  // Writer thread only.
  std::unique_ptr<PartFile> file_;
  std::unique_ptr<IndexWriter> index_;
  DiskBudget budget_;
  std::vector<uint8_t> pending_;          // encoded events not yet written
  std::vector<size_t> pending_ends_;
  std::vector<const Event*> pending_events_;
  int64_t next_event_number_ = 0;
  int64_t next_seek_utime_ = INT64_MIN;
  int64_t retry_open_utime_ = INT64_MIN;  // after a failed open, not before this (steady clock, us)
  std::optional<Loss> open_loss_;         // losses not yet noted in the index
  std::thread thread_;
};

}  // namespace bricklayer::logger
