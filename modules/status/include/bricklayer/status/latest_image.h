// The latest camera frame and the latest projector image for the operator's page: an unattended
// exhibit's operator looks at the phone to see what the camera sees and what the projector shows.
//
// Only the newest image_t's bytes are kept (the camera publishes 30 a second; decoding each would cost
// the status host a core for nothing). A JPEG or PNG is served as it came. A raw frame (GRAY8, BGR8:
// tests and tools) is encoded to JPEG only when the page asks, and at most once a second of the node's
// bus clock: between encodings the previous JPEG is served.
//
// Thread safety: the node's thread stores (update, set_now), the HTTP server's thread reads (get); one
// mutex guards both, so a request never sees half a frame.
#pragma once

#include <cstdint>
#include <mutex>
#include <optional>
#include <string>

#include <nlohmann/json.hpp>

#include "bricklayer/image_t.hpp"

namespace bricklayer::status {

// One image as the page fetches it.
struct ServedImage {
  std::string bytes;
  std::string content_type;  // image/jpeg or image/png
};

class LatestImage {
 public:
  // How often a raw frame may be encoded, bus-clock microseconds.
  static constexpr int64_t kEncodeEveryUs = 1'000'000;

  // A malformed image (size disagreeing with data, unknown format, raw frame of the wrong length) is
  // refused: the previous one stays, the refusal is counted (bad()) and its reason returned.
  std::optional<std::string> update(const image_t& image, int64_t received_utime);
  void set_now(int64_t utime);

  // The latest image, encoded if needed; nullopt before any was seen (or a raw frame OpenCV cannot encode).
  std::optional<ServedImage> get();
  // {"seen": false} or {"seen": true, "age_s", "width", "height", "format", "source", "frame_number"}.
  nlohmann::json to_json() const;
  int64_t received() const;
  int64_t bad() const;
  int64_t encodings() const;

 private:
  mutable std::mutex mutex_;
  std::optional<image_t> image_;
  int64_t received_utime_ = 0;
  int64_t now_ = 0;
  int64_t received_ = 0, bad_ = 0, encodings_ = 0;
  // The last encoding of a raw frame, and when (bus clock).
  std::optional<ServedImage> encoded_;
  int64_t encoded_utime_ = INT64_MIN;
};

}  // namespace bricklayer::status
