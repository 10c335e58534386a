#include "bricklayer/frames/decode_ahead.h"

#include <algorithm>
#include <atomic>
#include <cstring>

#include "bricklayer/frames/image_codec.h"

namespace bricklayer::frames {
namespace {

std::atomic<DecodeAhead*> g_installed{nullptr};

bool same_frame(const image_t& a, const image_t& b) {
  return a.utime == b.utime && a.frame_number == b.frame_number && a.width == b.width && a.height == b.height &&
         a.format == b.format && a.size == b.size && a.source == b.source && a.data.size() == b.data.size() &&
         (a.data.empty() || std::memcmp(a.data.data(), b.data.data(), a.data.size()) == 0);
}

}  // namespace

DecodeAhead::DecodeAhead(size_t max_frames) : max_frames_(std::max<size_t>(1, max_frames)) {
  worker_ = std::thread([this] { work(); });
}

DecodeAhead::~DecodeAhead() {
  DecodeAhead* self = this;
  g_installed.compare_exchange_strong(self, nullptr);
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stopping_ = true;
  }
  wake_worker_.notify_all();
  worker_.join();
}

void DecodeAhead::install(DecodeAhead* ahead) { g_installed.store(ahead); }
DecodeAhead* DecodeAhead::installed() { return g_installed.load(); }

void DecodeAhead::offer(image_t image) {
  auto entry = std::make_shared<Entry>();
  entry->image = std::move(image);
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (kept_.size() >= max_frames_) {
      // Forget the oldest (and do not decode it any more if it is still waiting).
      const auto oldest = kept_.front();
      kept_.pop_front();
      pending_.erase(std::remove(pending_.begin(), pending_.end(), oldest), pending_.end());
    }
    kept_.push_back(entry);
    pending_.push_back(entry);
  }
  wake_worker_.notify_one();
}

std::optional<cv::Mat> DecodeAhead::take(const image_t& image, std::string* error) {
  std::unique_lock<std::mutex> lock(mutex_);
  const auto it = std::find_if(kept_.begin(), kept_.end(),
                               [&](const std::shared_ptr<Entry>& e) { return same_frame(e->image, image); });
  if (it == kept_.end()) {
    ++missed_;
    return std::nullopt;
  }
  const std::shared_ptr<Entry> entry = *it;
  for (auto skipped = kept_.begin(); skipped != it; ++skipped)
    pending_.erase(std::remove(pending_.begin(), pending_.end(), *skipped), pending_.end());
  kept_.erase(kept_.begin(), it + 1);
  decoded_.wait(lock, [&] { return entry->done; });
  ++taken_;
  if (error && entry->decoded.empty()) *error = entry->error;
  return entry->decoded;
}

size_t DecodeAhead::taken() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return taken_;
}

size_t DecodeAhead::missed() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return missed_;
}

void DecodeAhead::work() {
  std::unique_lock<std::mutex> lock(mutex_);
  for (;;) {
    wake_worker_.wait(lock, [&] { return stopping_ || !pending_.empty(); });
    if (stopping_) return;
    const std::shared_ptr<Entry> entry = pending_.front();
    pending_.pop_front();
    lock.unlock();
    std::string error;
    cv::Mat decoded = decode_image_here(entry->image, &error);
    lock.lock();
    entry->decoded = std::move(decoded);
    entry->error = std::move(error);
    entry->done = true;
    decoded_.notify_all();
  }
}

}  // namespace bricklayer::frames
