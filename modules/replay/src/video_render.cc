#include "bricklayer/replay/video_render.h"

#include <cmath>
#include <ctime>
#include <stdexcept>

#include <opencv2/imgproc.hpp>
#include <opencv2/videoio.hpp>

#include "bricklayer/common/channels.h"
#include "bricklayer/frames/image_codec.h"
#include "bricklayer/image_t.hpp"
#include "bricklayer/projector_state_t.hpp"
#include "bricklayer/runtime/codec.h"

namespace bricklayer::replay {
namespace {

std::string time_of_day(int64_t utime) {
  const std::time_t s = static_cast<std::time_t>(utime / 1'000'000);
  std::tm tm{};
  gmtime_r(&s, &tm);
  char buf[32];
  std::snprintf(buf, sizeof buf, "%02d:%02d:%02d.%03d UTC", tm.tm_hour, tm.tm_min, tm.tm_sec,
                static_cast<int>((utime / 1000) % 1000));
  return buf;
}

const char* verdict_text(const prediction_t& p) {
  if (p.status != prediction_t::STATUS_OK) return "no verdict";
  switch (p.verdict) {
    case prediction_t::VERDICT_STABLE: return "stable";
    case prediction_t::VERDICT_FALLS: return "falls";
    case prediction_t::VERDICT_KNIFE_EDGE: return "knife edge";
    default: return "?";
  }
}

const char* round_text(const round_t& r) {
  switch (r.state) {
    case round_t::STATE_RUNNING: return "round running";
    case round_t::STATE_ENDED: return "round ended";
    default: return "between rounds";
  }
}

// A side of the picture: the image fitted into the side's size, or a notice on black.
cv::Mat side(const cv::Mat& image, const std::string& notice) {
  cv::Mat out(VideoRenderer::kSideHeight, VideoRenderer::kSideWidth, CV_8UC3, cv::Scalar(0, 0, 0));
  if (!image.empty()) {
    cv::Mat bgr = image;
    if (image.channels() == 1) cv::cvtColor(image, bgr, cv::COLOR_GRAY2BGR);
    cv::resize(bgr, out, out.size(), 0, 0, cv::INTER_AREA);
  } else {
    cv::putText(out, notice, {20, VideoRenderer::kSideHeight / 2}, cv::FONT_HERSHEY_SIMPLEX, 0.8, {200, 200, 200}, 2);
  }
  return out;
}

}  // namespace

VideoRenderer::VideoRenderer(VideoOptions options) : options_(std::move(options)) {
  if (options_.path.empty()) throw std::invalid_argument("--video needs a file name");
  if (!(options_.speed > 0 && options_.speed <= 1000)) throw std::invalid_argument("--speed must be in (0, 1000]");
  if (!(options_.fps > 0 && options_.fps <= 120)) throw std::invalid_argument("the video's rate must be in (0, 120]");
}

VideoRenderer::~VideoRenderer() = default;

cv::Mat VideoRenderer::compose(const cv::Mat& camera, int64_t utime) const {
  cv::Mat out(kSideHeight + kStripHeight, 2 * kSideWidth, CV_8UC3, cv::Scalar(32, 32, 32));
  side(camera, "no camera frame").copyTo(out(cv::Rect(0, 0, kSideWidth, kSideHeight)));
  side(projector_, "no projector image yet").copyTo(out(cv::Rect(kSideWidth, 0, kSideWidth, kSideHeight)));
  std::string line = time_of_day(utime);
  if (prediction_) {
    line += "   score " + std::to_string(prediction_->score) + "   " + verdict_text(*prediction_) + "   " +
            std::to_string(prediction_->num_blocks) + " blocks";
  }
  if (round_) line += std::string("   ") + round_text(*round_) + "   MAX " + std::to_string(round_->max_score);
  cv::putText(out, line, {16, kSideHeight + 42}, cv::FONT_HERSHEY_SIMPLEX, 0.8, {255, 255, 255}, 2);
  return out;
}

int64_t VideoRenderer::index_of(int64_t utime) const {
  // Video frame k shows log time first + k / fps * speed.
  return std::llround(static_cast<double>(utime - first_utime_) / 1e6 / options_.speed * options_.fps);
}

void VideoRenderer::write_before(int64_t index) {
  for (; summary_.video_frames < index; ++summary_.video_frames) writer_->write(picture_);
}

void VideoRenderer::observe(const runtime::LogEvent& e) {
  if (e.channel == channel(kPredictionChannel)) {
    if (auto p = runtime::decode<prediction_t>(e.data)) prediction_ = std::move(p);
    return;
  }
  if (e.channel == channel(kRoundChannel)) {
    if (auto r = runtime::decode<round_t>(e.data)) round_ = std::move(r);
    return;
  }
  if (e.channel == channel(kProjectorChannel)) {
    if (auto p = runtime::decode<projector_state_t>(e.data)) {
      std::string error;
      cv::Mat image = frames::decode_image(p->image, &error);
      if (image.empty()) ++summary_.bad_frames;
      projector_ = image;
    }
    return;
  }
  if (e.channel != channel(kImageChannel)) return;
  const auto image = runtime::decode<image_t>(e.data);
  if (!image) return;
  std::string error;
  const cv::Mat camera = frames::decode_image(*image, &error);
  if (camera.empty()) ++summary_.bad_frames;
  if (!writer_) {
    const bool avi = options_.path.size() > 4 && options_.path.substr(options_.path.size() - 4) == ".avi";
    const int fourcc = avi ? cv::VideoWriter::fourcc('M', 'J', 'P', 'G') : cv::VideoWriter::fourcc('m', 'p', '4', 'v');
    writer_ = std::make_unique<cv::VideoWriter>(options_.path, fourcc, options_.fps,
                                                cv::Size(2 * kSideWidth, kSideHeight + kStripHeight));
    if (!writer_->isOpened()) throw std::runtime_error("cannot write the video " + options_.path + " (OpenCV's VideoWriter)");
    first_utime_ = e.utime;
  }
  // The picture shown until now fills the video up to this frame's moment; then this frame is shown (two
  // frames on one video frame: the later one).
  if (!picture_.empty()) write_before(index_of(e.utime));
  picture_ = compose(camera, e.utime);
  ++summary_.camera_frames;
  last_utime_ = e.utime;
}

VideoSummary VideoRenderer::finish() {
  if (!writer_) throw std::runtime_error("no camera frame in the range: nothing to render");
  write_before(index_of(last_utime_) + 1);
  writer_->release();
  summary_.duration_s = static_cast<double>(summary_.video_frames) / options_.fps;
  return summary_;
}

}  // namespace bricklayer::replay
