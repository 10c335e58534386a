// Decodes frames on a second thread ahead of the node that will ask for them. A replay reads its log
// ahead of what it delivers, offers each frame here, and vision's decode_image then finds frame n+1
// already decoded while it works on frame n: on a 2-core machine decoding (a third of vision's time)
// overlaps the rest. The result is the same decoder's output on the same bytes, so nothing a node
// publishes changes, only when it is ready.
//
// Installed process-wide (install()), because the node that decodes is built by the code under test and
// knows nothing of replays; while none is installed decode_image decodes on the caller's thread.
// Bounded: at most max_frames offered frames are kept (the oldest forgotten first, then decoded on the
// caller's thread when asked for), so a node that never asks for a frame never stalls the reader.
#pragma once

#include <condition_variable>
#include <cstddef>
#include <deque>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>

#include <opencv2/core.hpp>

#include "bricklayer/image_t.hpp"

namespace bricklayer::frames {

class DecodeAhead {
 public:
  explicit DecodeAhead(size_t max_frames = 32);
  ~DecodeAhead();  // uninstalls itself if installed, joins the thread
  DecodeAhead(const DecodeAhead&) = delete;
  DecodeAhead& operator=(const DecodeAhead&) = delete;

  // Queues a frame for decoding.
  void offer(image_t image);
  // The decoded frame (and its decode error) if these very bytes were offered and not yet taken or
  // forgotten, waiting for its decoding; the frames offered before it are dropped (a node asks in the
  // order they were offered). nullopt: not offered, decode it here.
  std::optional<cv::Mat> take(const image_t& image, std::string* error);

  // decode_image consults this one from now on (nullptr: none).
  static void install(DecodeAhead* ahead);
  static DecodeAhead* installed();

  // Taken ready / taken after a wait / asked but not there (decoded by the caller).
  size_t taken() const;
  size_t missed() const;

 private:
  struct Entry {
    image_t image;
    cv::Mat decoded;
    std::string error;
    bool done = false;
  };
  void work();

  const size_t max_frames_;
  mutable std::mutex mutex_;
  std::condition_variable wake_worker_, decoded_;
  std::deque<std::shared_ptr<Entry>> kept_;     // offered, not yet taken or forgotten, in order
  std::deque<std::shared_ptr<Entry>> pending_;  // not yet decoded, in order
  bool stopping_ = false;
  size_t taken_ = 0, missed_ = 0;
  std::thread worker_;
};

}  // namespace bricklayer::frames
