// bricklayer-bench-simcam: render time of one simulated camera frame (median and p99) for random piles
// at each nuisance level, at 640x480 and 1280x720, with and without projector light and with a random
// (distorted) camera setup. --out DIR also writes one example PNG per configuration.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "bricklayer/common/flags.h"
#include "bricklayer/piles/random_pile.h"
#include "bricklayer/simcam/render.h"

namespace {

using namespace bricklayer;
using namespace bricklayer::simcam;

cv::Mat red_blue_projection(const core::Stack& stack, const CameraSetup& cam, const ProjectorSetup& proj) {
  // Every block lit blue, every third red, in projector pixels (what projection would show).
  cv::Mat img(proj.size, CV_8UC3, cv::Scalar(0, 0, 0));
  cv::Matx33d to_proj = proj.projector_to_rectified.inv();
  for (size_t i = 0; i < stack.blocks.size(); ++i) {
    const auto& b = stack.blocks[i];
    double u0 = cam.board.to_px_x(b.x), u1 = u0 + cam.board.block_length_px;
    double v1 = cam.board.surface_y_px - b.row * cam.board.block_height_px, v0 = v1 - cam.board.block_height_px;
    std::vector<cv::Point> poly;
    for (auto p : {cv::Point2d(u0, v0), cv::Point2d(u1, v0), cv::Point2d(u1, v1), cv::Point2d(u0, v1)}) {
      cv::Vec3d q = to_proj * cv::Vec3d(p.x, p.y, 1);
      poly.emplace_back(static_cast<int>(q[0] / q[2]), static_cast<int>(q[1] / q[2]));
    }
    cv::fillConvexPoly(img, poly, i % 3 == 0 ? cv::Scalar(0, 0, 255) : cv::Scalar(255, 0, 0));
  }
  return img;
}

int Main(int argc, char** argv) {
  Flags flags("bricklayer-bench-simcam", "Render time of simulated camera frames (median, p99).");
  flags.add("frames", "200", "frames per configuration");
  flags.add("blocks", "60", "blocks per random pile");
  flags.add("out", "", "directory for one example PNG per configuration (optional)");
  if (!flags.parse(argc, argv)) return 0;
  const int frames = static_cast<int>(flags.get_int("frames"));
  const std::string out = flags.get("out");
  if (frames < 1) throw FlagError("--frames must be at least 1");
  if (!out.empty()) std::filesystem::create_directories(out);
  piles::PileOptions pile;
  pile.blocks = static_cast<int>(flags.get_int("blocks"));

  std::printf("%-10s %-8s %-10s %-10s %10s %10s\n", "size", "level", "setup", "projector", "median_ms", "p99_ms");
  for (cv::Size size : {cv::Size(640, 480), cv::Size(1280, 720)}) {
    for (bool random_setup : {false, true}) {
      CameraSetup cam = random_setup ? CameraSetup::random(7, size) : CameraSetup::default_for(size);
      ProjectorSetup proj = random_setup ? ProjectorSetup::random(7) : ProjectorSetup{};
      Renderer renderer(cam, proj);
      for (int level = 0; level <= 3; ++level) {
        for (bool projecting : {false, true}) {
          Nuisance n = Nuisance::level(level);
          std::vector<double> ms;
          for (int f = 0; f < frames; ++f) {
            core::Stack stack = piles::random_pile(static_cast<uint64_t>(f % 20), pile);
            cv::Mat light = projecting ? red_blue_projection(stack, cam, proj) : cv::Mat();
            auto t0 = std::chrono::steady_clock::now();
            Rendered r = renderer.render(stack, n, projecting ? &light : nullptr, static_cast<uint64_t>(f));
            ms.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
            if (f == 0 && !out.empty()) {
              std::string name = out + "/" + std::to_string(size.width) + "x" + std::to_string(size.height) + "-" + n.name +
                                 (random_setup ? "-random" : "-default") + (projecting ? "-projected" : "") + ".png";
              cv::imwrite(name, r.bgr);
            }
          }
          std::sort(ms.begin(), ms.end());
          double median = ms[ms.size() / 2];
          double p99 = ms[std::min(ms.size() - 1, static_cast<size_t>(0.99 * static_cast<double>(ms.size())))];
          std::printf("%-10s %-8s %-10s %-10s %10.2f %10.2f\n",
                      (std::to_string(size.width) + "x" + std::to_string(size.height)).c_str(), n.name.c_str(),
                      random_setup ? "random" : "default", projecting ? "red/blue" : "off", median, p99);
        }
      }
    }
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) { return bricklayer::run_main("bricklayer-bench-simcam", &Main, argc, argv); }
