// decode_image: camera JPEGs decode exactly as cv::imdecode decodes them (libjpeg-turbo's own API is only
// a faster road to the same pixels), greyscale JPEGs stay grey, and bad frames are errors, not crashes.
#include <catch2/catch.hpp>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "bricklayer/frames/image_codec.h"

using namespace bricklayer;

namespace {

cv::Mat test_frame(int width, int height, uint64_t seed) {
  cv::Mat img(height, width, CV_8UC3);
  cv::RNG rng(seed);
  rng.fill(img, cv::RNG::UNIFORM, 0, 255);
  cv::GaussianBlur(img, img, {9, 9}, 3);
  cv::line(img, {width / 3, 0}, {width / 3, height - 1}, {0, 0, 0}, 3);
  return img;
}

image_t jpeg_message(const cv::Mat& img, int quality) {
  image_t m{};
  m.width = img.cols;
  m.height = img.rows;
  m.format = image_t::FORMAT_JPEG;
  cv::imencode(".jpg", img, m.data, {cv::IMWRITE_JPEG_QUALITY, quality});
  m.size = static_cast<int32_t>(m.data.size());
  return m;
}

}  // namespace

TEST_CASE("JPEG frames decode to exactly the pixels cv::imdecode gives") {
  for (auto [w, h, q] : {std::tuple{640, 480, 90}, {1280, 720, 75}, {33, 17, 100}}) {
    for (bool grey : {false, true}) {
      cv::Mat img = test_frame(w, h, static_cast<uint64_t>(w + q));
      if (grey) cv::cvtColor(img, img, cv::COLOR_BGR2GRAY);
      const image_t m = jpeg_message(img, q);
      std::string error;
      const cv::Mat ours = frames::decode_image(m, &error);
      const cv::Mat reference = cv::imdecode(m.data, cv::IMREAD_UNCHANGED);
      INFO(w << "x" << h << " quality " << q << (grey ? " grey" : " colour") << ": " << error);
      REQUIRE(error.empty());
      REQUIRE(ours.size() == reference.size());
      REQUIRE(ours.type() == reference.type());
      CHECK(cv::norm(ours, reference, cv::NORM_INF) == 0);
    }
  }
}

TEST_CASE("a JPEG whose body is damaged or whose size disagrees with the message is an error or OpenCV's frame") {
  const cv::Mat img = test_frame(640, 480, 3);
  image_t m = jpeg_message(img, 90);
  std::string error;
  image_t wrong = m;
  wrong.width = 320;
  CHECK(frames::decode_image(wrong, &error).empty());
  CHECK_FALSE(error.empty());
  // Scramble the entropy-coded middle: TurboJPEG reports it, the frame then goes through cv::imdecode,
  // which either refuses it (an error) or returns what libjpeg made of it, as before.
  image_t damaged = m;
  for (size_t i = damaged.data.size() / 2; i < damaged.data.size() / 2 + 200; ++i) damaged.data[i] ^= 0x5A;
  error.clear();
  const cv::Mat out = frames::decode_image(damaged, &error);
  CHECK((out.empty() ? !error.empty() : out.size() == img.size()));
  image_t truncated = m;
  truncated.data.resize(truncated.data.size() / 2);
  error.clear();
  CHECK(frames::decode_image(truncated, &error).empty());
  CHECK_FALSE(error.empty());
}
