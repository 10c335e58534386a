#include "bricklayer/logger/event_writer.h"

#include <chrono>
#include <cstring>
#include <filesystem>
#include <set>
#include <stdexcept>
#include <system_error>
#include <utility>

#include "bricklayer/common/log.h"
#include "bricklayer/runtime/log_file.h"

namespace bricklayer::logger {
namespace fs = std::filesystem;
namespace {

// Encoded events are written in pieces of at most this many bytes (and at least every flush period).
constexpr size_t kMaxPendingBytes = 4u << 20;
// After a file could not be opened (the disk is full), try again no sooner than this.
constexpr int64_t kRetryOpenUs = 1'000'000;
// A seek point in the index about this often.
constexpr int64_t kSeekEveryUs = 1'000'000;

int64_t steady_us() {
  return std::chrono::duration_cast<std::chrono::microseconds>(std::chrono::steady_clock::now().time_since_epoch())
      .count();
}

BudgetOptions budget_options(const WriterOptions& o) {
  BudgetOptions b;
  const fs::path base(o.base);
  b.folder = base.has_parent_path() ? base.parent_path().string() : ".";
  std::error_code ec;
  fs::create_directories(b.folder, ec);
  if (ec) throw std::runtime_error("cannot create the log directory " + b.folder + ": " + ec.message());
  b.prefix = o.series_prefix.empty() ? base.filename().string() + "." : o.series_prefix;
  b.max_bytes = o.budget_bytes;
  b.min_free_bytes = o.min_free_bytes;
  return b;
}

}  // namespace

EventWriter::EventWriter(WriterOptions options, std::function<void(const Event&)> on_written)
    : options_(std::move(options)),
      on_written_(std::move(on_written)),
      series_(options_.base, options_.rotate),
      budget_(budget_options(options_)) {
  if (options_.split_bytes < 0) throw std::invalid_argument("split size must be >= 0 (0 = never split)");
  if (options_.flush_ms < 0) throw std::invalid_argument("flush period must be >= 0 ms");
  if (options_.max_unwritten_bytes <= 0) throw std::invalid_argument("the unwritten-queue bound must be > 0 bytes");
  if (options_.budget_bytes < 0 || options_.min_free_bytes < 0) throw std::invalid_argument("budgets must be >= 0");
  if (options_.budget_bytes > 0 && options_.split_bytes > 0 && 2 * options_.split_bytes > options_.budget_bytes)
    throw std::invalid_argument("the split size must be at most half the budget (the open file is never deleted)");
  if (options_.index && options_.rotate == 0) {
    index_ = std::make_unique<IndexWriter>(options_.base + ".index");
    std::lock_guard lock(mutex_);
    stats_.index_file = index_->path();
  }
  // On the caller's thread: a path that cannot be written is an error at start, not later.
  if (!open_next(0)) {
    std::string why;
    {
      std::lock_guard lock(mutex_);
      why = stats_.last_error;
    }
    throw std::runtime_error(why);
  }
  update_disk_stats();
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

void EventWriter::note(Moment moment) {
  {
    std::lock_guard lock(mutex_);
    notes_.push_back(std::move(moment));
  }
  wake_.notify_one();
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
  commit();
  note_losses();
  close_current();
  update_disk_stats();
}

WriterStats EventWriter::stats() const {
  std::lock_guard lock(mutex_);
  return stats_;
}

bool EventWriter::open_next(int64_t first_utime) {
  close_current();
  std::string path;
  try {
    path = series_.next();
    // Room for the file's first events is made when they are written; an empty file costs nothing.
    file_ = std::make_unique<PartFile>(path);
  } catch (const std::exception& e) {
    std::lock_guard lock(mutex_);
    stats_.last_error = e.what();
    stats_.current_file.clear();
    return false;
  }
  next_event_number_ = 0;
  next_seek_utime_ = INT64_MIN;
  if (index_ && first_utime > 0) index_->part(path, first_utime);
  std::lock_guard lock(mutex_);
  ++stats_.files;
  stats_.current_file = path;
  return true;
}

void EventWriter::close_current() {
  if (!file_) return;
  // What is closed must be on the disk: a power cut after a split loses at most the open file's tail.
  const bool failed = file_->failed();
  file_->close();
  if (failed && file_->events() == 0) {
    std::error_code ec;
    fs::remove(file_->path(), ec);  // nothing in it: an empty file would only look like a recording
  }
  file_.reset();
  std::lock_guard lock(mutex_);
  stats_.current_file.clear();
}

void EventWriter::lose(size_t count, int64_t from, int64_t to, const std::string& reason) {
  if (count == 0) return;
  if (!open_loss_) open_loss_ = Loss{0, from, to, reason};
  open_loss_->events += static_cast<int64_t>(count);
  open_loss_->to_utime = to;
  if (open_loss_->reason.find(reason) == std::string::npos) open_loss_->reason += ", " + reason;
  std::lock_guard lock(mutex_);
  stats_.lost += static_cast<int64_t>(count);
}

void EventWriter::note_losses() {
  if (!open_loss_ || !index_) return;
  const int64_t failed = index_->failed_lines();
  index_->loss(*open_loss_);
  if (index_->failed_lines() == failed) open_loss_.reset();  // else noted once there is room
}

void EventWriter::update_disk_stats() {
  const int64_t used = budget_.used_bytes();
  const int64_t free = budget_.free_bytes();
  std::lock_guard lock(mutex_);
  stats_.series_bytes = used;
  stats_.free_bytes = free;
  stats_.deleted_files = budget_.deleted_files();
  stats_.deleted_bytes = budget_.deleted_bytes();
}

void EventWriter::write(const std::deque<Event>& batch) {
  for (const Event& e : batch) {
    const size_t size = static_cast<size_t>(file_size_of(e));
    const int64_t in_file = file_ ? file_->size() : 0;
    if (options_.split_bytes > 0 && file_ && in_file + static_cast<int64_t>(pending_.size()) > 0 &&
        in_file + static_cast<int64_t>(pending_.size() + size) > options_.split_bytes) {
      commit();
      if (file_) open_next(e.utime);  // a failed open is retried by commit(), and its events counted
    }
    const std::vector<uint8_t> bytes =
        runtime::encode_log_event(next_event_number_ + static_cast<int64_t>(pending_events_.size()), e.utime, e.channel,
                                  e.data.data(), e.data.size());
    pending_.insert(pending_.end(), bytes.begin(), bytes.end());
    pending_ends_.push_back(pending_.size());
    pending_events_.push_back(&e);
    if (pending_.size() >= kMaxPendingBytes) commit();
  }
}

void EventWriter::commit() {
  if (pending_events_.empty()) return;
  const size_t n = pending_events_.size();
  const int64_t from = pending_events_.front()->utime, to = pending_events_.back()->utime;
  auto clear = [this] {
    pending_.clear();
    pending_ends_.clear();
    pending_events_.clear();
  };
  if (!file_) {
    if (steady_us() < retry_open_utime_ || !open_next(from)) {
      retry_open_utime_ = steady_us() + kRetryOpenUs;
      lose(n, from, to, "no file could be opened");
      clear();
      return;
    }
  }
  std::set<std::string> keep{file_->path()};
  if (index_) keep.insert(index_->path());
  if (!budget_.make_room(static_cast<int64_t>(pending_.size()), keep)) {
    const bool over_budget =
        options_.budget_bytes > 0 && budget_.used_bytes() + static_cast<int64_t>(pending_.size()) > options_.budget_bytes;
    lose(n, from, to, over_budget ? "over the budget" : "disk full");
    clear();
    update_disk_stats();
    return;
  }
  if (index_ && file_->events() == 0 && file_->size() == 0) index_->part(file_->path(), from);
  const int64_t start = file_->size();
  const size_t k = file_->append(pending_, pending_ends_);
  const int64_t kept_bytes = k ? static_cast<int64_t>(pending_ends_[k - 1]) : 0;
  budget_.wrote(kept_bytes);
  for (size_t i = 0; i < k; ++i) {
    const Event& e = *pending_events_[i];
    if (index_ && e.utime >= next_seek_utime_) {
      index_->seek(file_->path(), e.utime, start + (i ? static_cast<int64_t>(pending_ends_[i - 1]) : 0));
      next_seek_utime_ = e.utime + kSeekEveryUs;
    }
    if (on_written_) on_written_(e);
  }
  next_event_number_ += static_cast<int64_t>(k);
  {
    std::lock_guard lock(mutex_);
    stats_.written += static_cast<int64_t>(k);
    stats_.bytes += kept_bytes;
    if (k < n) {
      ++stats_.write_errors;
      stats_.last_error = file_->error();
    }
  }
  if (k < n) {
    log::error(file_->error(), "; ", n - k, " event(s) not kept, the next ones go into a new file");
    lose(n - k, pending_events_[k]->utime, to, file_->disk_full() ? "disk full" : "write error");
    close_current();  // never append behind a failed write
  } else {
    note_losses();
  }
  clear();
  update_disk_stats();
}

void EventWriter::run() {
  using Clock = std::chrono::steady_clock;
  const auto period = std::chrono::milliseconds(options_.flush_ms);
  auto next_flush = Clock::now() + period;
  std::deque<Event> batch;
  std::deque<Moment> notes;
  for (;;) {
    bool stopping = false, new_file = false;
    int64_t taken = 0;
    {
      std::unique_lock lock(mutex_);
      // The queue is the write buffer: it is written at the end of every period (at once with flush_ms
      // 0, or when a piece's worth is waiting), so bursts cost one write.
      auto urgent = [&] {
        return stopping_ || new_file_requested_ || !notes_.empty() ||
               (!queue_.empty() && (options_.flush_ms == 0 || queued_bytes_ >= static_cast<int64_t>(kMaxPendingBytes)));
      };
      if (options_.flush_ms == 0)
        wake_.wait(lock, urgent);
      else
        wake_.wait_until(lock, next_flush, urgent);
      const auto now = Clock::now();
      stopping = stopping_;
      new_file = std::exchange(new_file_requested_, false) && !stopping;
      if (options_.flush_ms == 0 || now >= next_flush || stopping || new_file ||
          queued_bytes_ >= static_cast<int64_t>(kMaxPendingBytes)) {
        batch.swap(queue_);
        for (const Event& e : batch) taken += file_size_of(e);
      }
      notes.swap(notes_);
      stats_.moments += static_cast<int64_t>(notes.size());
      if (now >= next_flush) next_flush = now + period;
    }
    write(batch);
    commit();  // pending_ points into batch: written before batch is cleared
    batch.clear();
    for (const Moment& m : notes)
      if (index_) index_->moment(m);
    notes.clear();
    {
      std::lock_guard lock(mutex_);
      queued_bytes_ -= taken;
      stats_.queued_bytes = queued_bytes_;
    }
    if (new_file) {
      // After the batch: what arrived before the request is in the old file. Even with nothing to
      // write the file is closed, so the operator can move it away.
      open_next(0);
    }
    if (stopping) {
      std::lock_guard lock(mutex_);
      if (queue_.empty()) break;  // a push racing with stop() was refused; anything queued is written
    }
  }
}

}  // namespace bricklayer::logger
