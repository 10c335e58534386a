#include "bricklayer/status/latest_image.h"

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

namespace bricklayer::status {

namespace {
const char* format_name(int32_t f) {
  switch (f) {
    case image_t::FORMAT_JPEG: return "jpeg";
    case image_t::FORMAT_PNG: return "png";
    case image_t::FORMAT_GRAY8: return "gray8";
    case image_t::FORMAT_BGR8: return "bgr8";
    default: return "unknown";
  }
}
}  // namespace

std::optional<std::string> LatestImage::update(const image_t& image, int64_t received_utime) {
  std::optional<std::string> why;
  const size_t n = image.data.size();
  if (image.size < 0 || static_cast<size_t>(image.size) != n) {
    why = "size " + std::to_string(image.size) + " but " + std::to_string(n) + " bytes of data";
  } else if (n == 0) {
    why = "no data";
  } else if (image.format == image_t::FORMAT_GRAY8 || image.format == image_t::FORMAT_BGR8) {
    const size_t channels = image.format == image_t::FORMAT_GRAY8 ? 1 : 3;
    if (image.width <= 0 || image.height <= 0 ||
        n != static_cast<size_t>(image.width) * static_cast<size_t>(image.height) * channels)
      why = "a raw " + std::string(format_name(image.format)) + " frame of " + std::to_string(image.width) + "x" +
            std::to_string(image.height) + " with " + std::to_string(n) + " bytes";
  } else if (image.format != image_t::FORMAT_JPEG && image.format != image_t::FORMAT_PNG) {
    why = "unknown format " + std::to_string(image.format);
  }
  std::lock_guard lock(mutex_);
  if (why) {
    ++bad_;
    return why;
  }
  ++received_;
  image_ = image;
  received_utime_ = received_utime;
  return std::nullopt;
}

void LatestImage::set_now(int64_t utime) {
  std::lock_guard lock(mutex_);
  now_ = utime;
}

std::optional<ServedImage> LatestImage::get() {
  std::lock_guard lock(mutex_);
  if (!image_) return std::nullopt;
  const image_t& im = *image_;
  if (im.format == image_t::FORMAT_JPEG || im.format == image_t::FORMAT_PNG)
    return ServedImage{std::string(im.data.begin(), im.data.end()),
                       im.format == image_t::FORMAT_JPEG ? "image/jpeg" : "image/png"};
  // A raw frame: encode at most once a second, else serve the last encoding (a few phones polling
  // must not turn into a JPEG encoder running flat out).
  if (encoded_ && now_ - encoded_utime_ < kEncodeEveryUs) return encoded_;
  const int type = im.format == image_t::FORMAT_GRAY8 ? CV_8UC1 : CV_8UC3;
  const cv::Mat m(im.height, im.width, type, const_cast<uint8_t*>(im.data.data()));
  std::vector<uint8_t> jpeg;
  if (!cv::imencode(".jpg", m, jpeg, {cv::IMWRITE_JPEG_QUALITY, 80})) return encoded_;
  ++encodings_;
  encoded_ = ServedImage{std::string(jpeg.begin(), jpeg.end()), "image/jpeg"};
  encoded_utime_ = now_;
  return encoded_;
}

nlohmann::json LatestImage::to_json() const {
  std::lock_guard lock(mutex_);
  if (!image_) return {{"seen", false}};
  return {{"seen", true},
          {"age_s", static_cast<double>(now_ - received_utime_) * 1e-6},
          {"width", image_->width},
          {"height", image_->height},
          {"format", format_name(image_->format)},
          {"source", image_->source},
          {"frame_number", image_->frame_number}};
}

int64_t LatestImage::received() const {
  std::lock_guard lock(mutex_);
  return received_;
}
int64_t LatestImage::bad() const {
  std::lock_guard lock(mutex_);
  return bad_;
}
int64_t LatestImage::encodings() const {
  std::lock_guard lock(mutex_);
  return encodings_;
}

}  // namespace bricklayer::status
