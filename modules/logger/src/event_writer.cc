#include "bricklayer/logger/event_writer.h"

#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <stdexcept>
#include <utility>

#include "bricklayer/common/log.h"

namespace bricklayer::logger {

EventWriter::EventWriter(WriterOptions options, std::function<void(const Event&)> on_written)
    : options_(std::move(options)), on_written_(std::move(on_written)), series_(options_.base, options_.rotate) {
  if (options_.split_bytes < 0) throw std::invalid_argument("split size must be >= 0 (0 = never split)");
  if (options_.flush_ms < 0) throw std::invalid_argument("flush period must be >= 0 ms");
  if (options_.max_unwritten_bytes <= 0) throw std::invalid_argument("the unwritten-queue bound must be > 0 bytes");
  open_next();  // on the caller's thread: a path that cannot be written is an error at start, not later
  thread_ = std::thread([this] { run(); });
}

EventWriter::~EventWriter() { stop(); }

bool EventWriter::push(Event event) {
  const int64_t size = file_size_of(event);
  {
    std::lock_guard lock(mutex_);
    // One event larger than the whole bound is still accepted into an empty queue: a log must be able
    // to hold any message LCM can carry.
    if (stopping_ || (queued_bytes_ + size > options_.max_unwritten_bytes && !queue_.empty())) {
      ++stats_.dropped;
      return false;
    }
    queued_bytes_ += size;
    stats_.queued_bytes = queued_bytes_;
    if (queued_bytes_ > stats_.peak_queued_bytes) stats_.peak_queued_bytes = queued_bytes_;
    queue_.push_back(std::move(event));
  }
  wake_.notify_one();
  return true;
}

void EventWriter::request_new_file() {
  {
    std::lock_guard lock(mutex_);
    new_file_requested_ = true;
  }
  wake_.notify_one();
}

void EventWriter::stop() {
  {
    std::lock_guard lock(mutex_);
    if (stopping_ && !thread_.joinable()) return;
    stopping_ = true;
  }
  wake_.notify_one();
  if (thread_.joinable()) thread_.join();
  close_current();
}

WriterStats EventWriter::stats() const {
  std::lock_guard lock(mutex_);
  return stats_;
}

void EventWriter::open_next() {
  close_current();
  const std::string path = series_.next();
  auto file = std::make_unique<lcm::LogFile>(path, "w");
  if (!file->good() || !file->getFilePtr())
    throw std::runtime_error("cannot open the log file " + path + " for writing: " + std::strerror(errno));
  file_ = std::move(file);
  file_bytes_ = 0;
  std::lock_guard lock(mutex_);
  ++stats_.files;
  stats_.current_file = path;
}

void EventWriter::close_current() {
  if (!file_) return;
  // What is closed must be on the disk: a power cut after a split loses at most the open file's tail.
  std::fflush(file_->getFilePtr());
  ::fsync(::fileno(file_->getFilePtr()));
  file_.reset();
}

void EventWriter::write(const Event& e) {
  const int64_t size = file_size_of(e);
  if (options_.split_bytes > 0 && file_bytes_ > 0 && file_bytes_ + size > options_.split_bytes) {
    try {
      open_next();
    } catch (const std::exception& ex) {
      // Keep logging into nothing rather than dying: every refused event is a counted error.
      log::error("cannot start a new log file: ", ex.what());
    }
  }
  lcm::LogEvent le{};
  le.eventnum = 0;  // numbered by the file
  le.timestamp = e.utime;
  le.channel = e.channel;
  le.datalen = static_cast<int32_t>(e.data.size());
  le.data = const_cast<uint8_t*>(e.data.data());
  const bool ok = file_ && file_->writeEvent(&le) == 0;
  std::lock_guard lock(mutex_);
  if (ok) {
    file_bytes_ += size;
    ++stats_.written;
    stats_.bytes += size;
  } else {
    ++stats_.write_errors;
  }
}

void EventWriter::run() {
  using Clock = std::chrono::steady_clock;
  const auto period = std::chrono::milliseconds(options_.flush_ms);
  auto next_flush = Clock::now() + period;
  std::deque<Event> batch;
  bool dirty = false;
  for (;;) {
    bool stopping = false;
    {
      std::unique_lock lock(mutex_);
      auto work = [&] { return stopping_ || !queue_.empty() || new_file_requested_; };
      if (options_.flush_ms == 0)
        wake_.wait(lock, work);
      else
        wake_.wait_until(lock, next_flush, work);
      batch.swap(queue_);
      stopping = stopping_;
    }
    int64_t taken = 0;
    for (const Event& e : batch) {
      write(e);
      taken += file_size_of(e);
      if (on_written_) on_written_(e);
    }
    dirty = dirty || !batch.empty();
    batch.clear();
    bool new_file = false;
    {
      std::lock_guard lock(mutex_);
      queued_bytes_ -= taken;
      stats_.queued_bytes = queued_bytes_;
      new_file = std::exchange(new_file_requested_, false) && !stopping;
    }
    if (new_file) {
      // After the batch: what arrived before the request is in the old file. Even with nothing to
      // write the file is closed, so the operator can move it away.
      try {
        open_next();
      } catch (const std::exception& ex) {
        log::error("cannot start a new log file: ", ex.what());
      }
      dirty = false;
    }
    const auto now = Clock::now();
    if (dirty && (options_.flush_ms == 0 || now >= next_flush) && file_) {
      std::fflush(file_->getFilePtr());
      dirty = false;
    }
    if (now >= next_flush) next_flush = now + period;
    if (stopping) {
      std::lock_guard lock(mutex_);
      if (queue_.empty()) break;  // a push racing with stop() was refused; anything queued is written
    }
  }
  if (file_) std::fflush(file_->getFilePtr());
}

}  // namespace bricklayer::logger
