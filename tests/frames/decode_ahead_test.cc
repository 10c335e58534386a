// DecodeAhead: frames offered ahead come back from decode_image exactly as decoded on the caller's
// thread (bit for bit, errors too), in order, bounded, and a frame never offered (or forgotten) is simply
// decoded here.
#include <catch2/catch.hpp>

#include <opencv2/imgproc.hpp>

#include "bricklayer/frames/decode_ahead.h"
#include "bricklayer/frames/image_codec.h"

using namespace bricklayer;

namespace {

image_t frame(int number) {
  cv::Mat img(120, 160, CV_8UC3, cv::Scalar(40, 170, 90));
  cv::line(img, {10 + number % 140, 0}, {10 + number % 140, 119}, {0, 0, 0}, 3);
  cv::circle(img, {80, 60}, 5 + number % 30, {200, 20, 20}, -1);
  return frames::encode_image(img, number % 3 == 0 ? image_t::FORMAT_PNG : image_t::FORMAT_JPEG, 1000 + number, number,
                              "test");
}

bool identical(const cv::Mat& a, const cv::Mat& b) {
  return a.size() == b.size() && a.type() == b.type() && cv::norm(a, b, cv::NORM_INF) == 0;
}

}  // namespace

TEST_CASE("frames offered ahead decode to the same pixels, in order, and the decoder finds them") {
  frames::DecodeAhead ahead(8);
  frames::DecodeAhead::install(&ahead);
  std::vector<image_t> all;
  for (int i = 0; i < 40; ++i) all.push_back(frame(i));
  size_t offered = 0;
  for (size_t i = 0; i < all.size(); ++i) {
    while (offered < all.size() && offered < i + 6) ahead.offer(all[offered++]);  // six ahead, as a replay reads
    std::string error_ahead, error_here;
    const cv::Mat a = frames::decode_image(all[i], &error_ahead);
    const cv::Mat b = frames::decode_image_here(all[i], &error_here);
    REQUIRE(!a.empty());
    CHECK(identical(a, b));
    CHECK(error_ahead == error_here);
  }
  CHECK(ahead.taken() == 40);
  CHECK(ahead.missed() == 0);
  frames::DecodeAhead::install(nullptr);
}

TEST_CASE("a frame not offered, skipped or forgotten is decoded on the caller's thread") {
  frames::DecodeAhead ahead(4);
  frames::DecodeAhead::install(&ahead);
  for (int i = 0; i < 10; ++i) ahead.offer(frame(i));  // only 6..9 are kept
  std::string error;
  CHECK(identical(frames::decode_image(frame(2), &error), frames::decode_image_here(frame(2), &error)));
  CHECK(ahead.missed() == 1);
  // Asking for 8 drops 6 and 7 (a node asks in the order offered): asking for 7 then decodes here.
  CHECK(identical(frames::decode_image(frame(8), &error), frames::decode_image_here(frame(8), &error)));
  CHECK(ahead.taken() == 1);
  CHECK(identical(frames::decode_image(frame(7), &error), frames::decode_image_here(frame(7), &error)));
  CHECK(ahead.missed() == 2);
  // Same frame number and time, other bytes: not the frame offered.
  image_t other = frame(9);
  other.data[other.data.size() / 2] ^= 0x5a;
  std::string e1, e2;
  const cv::Mat a = frames::decode_image(other, &e1), b = frames::decode_image_here(other, &e2);
  CHECK(a.empty() == b.empty());
  if (!a.empty()) CHECK(identical(a, b));
  CHECK(e1 == e2);
  CHECK(ahead.missed() == 3);
  frames::DecodeAhead::install(nullptr);
}

TEST_CASE("a broken frame offered ahead gives the same error as decoded here, and destroyed it uninstalls itself") {
  image_t broken = frame(1);
  broken.data.resize(broken.data.size() / 2);
  broken.size = static_cast<int32_t>(broken.data.size());
  std::string here_error;
  CHECK(frames::decode_image_here(broken, &here_error).empty());
  REQUIRE(!here_error.empty());
  {
    frames::DecodeAhead ahead;
    frames::DecodeAhead::install(&ahead);
    ahead.offer(broken);
    std::string error;
    CHECK(frames::decode_image(broken, &error).empty());
    CHECK(error == here_error);
    CHECK(ahead.taken() == 1);
  }
  CHECK(frames::DecodeAhead::installed() == nullptr);
}
