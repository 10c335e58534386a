// bricklayer-bench-vision: accuracy and speed of the block detector on simcam-rendered frames of random
// seeded piles (10 to 80 blocks, built row by row, some blocks touching end to end), at every nuisance
// level, without and with red/blue projector light, at 640x480 and 1280x720 (the default setup at that size,
// through its true calibration, the projector scaled to it), and optionally through a random perspective +
// lens-distortion camera with its true calibration (--calibrated).
// Prints one markdown table row per configuration: recall, precision, row errors, |x error| median /
// p95 / max (block lengths) and detection time median / p99 (ms, from the decoded BGR frame to the blocks
// vision publishes: the detector and vision's publishing rules).
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include <opencv2/imgcodecs.hpp>

#include "evaluate.h"
#include "bricklayer/common/flags.h"
#include "bricklayer/core/splitmix64.h"
#include "bricklayer/piles/random_pile.h"
#include "bricklayer/simcam/render.h"
#include "bricklayer/detection/detector.h"
#include "bricklayer/vision/publishable.h"

namespace {

using namespace bricklayer;
using namespace bricklayer::detection;
using bricklayer::vision::make_publishable;

double percentile(std::vector<double> v, double q) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  return v[std::min(v.size() - 1, static_cast<size_t>(q * static_cast<double>(v.size())))];
}

// A stateless hash of a seed: one step of SplitMix64 from it.
uint64_t mix(uint64_t x) { return core::splitmix64(x); }

// Depth of every candidate line relative to its frame's median line, split by whether it lies on a true
// end line: the evidence for DetectorConfig::min_relative_depth (--line-stats).
struct LineDepths {
  std::vector<double> real, other;
};

void collect_line_stats(const simcam::CameraSetup& cam, const cv::Mat* projection, const simcam::ProjectorSetup& proj,
                        const simcam::Rendered& r, LineDepths& out) {
  DetectorConfig config;
  config.keep_lines = true;
  config.min_relative_depth = 0.0;  // every candidate, before the relative-depth test
  Detector detector(cam.board, config);
  if (projection) detector.set_projector_image(*projection, proj.size);
  const Detection d = detector.detect(r.bgr);
  std::vector<double> depths;
  for (const auto& l : d.line_list) depths.push_back(l.depth);
  std::nth_element(depths.begin(), depths.begin() + depths.size() / 2, depths.end());
  const double median = depths.empty() ? 1.0 : depths[depths.size() / 2];
  const double w = cam.line_width * cam.board.block_length_px;
  for (const auto& l : d.line_list) {
    bool real = false;
    for (const auto& tb : r.truth) {
      if (tb.row != l.row) continue;
      const double left = cam.board.to_px_x(tb.x) + 0.5 * w, right = cam.board.to_px_x(tb.x + 1) - 0.5 * w;
      real = real || std::abs(l.x_px - left) < 2.5 || std::abs(l.x_px - right) < 2.5;
    }
    (real ? out.real : out.other).push_back(l.depth / median);
  }
}

struct Totals {
  int frames = 0, truth = 0, detected = 0, matched = 0, row_wrong = 0;
  std::vector<double> dx, ms;
};

// Random pile number `index`: 10..80 blocks, gaps from touching (0) to 0.8 block lengths.
core::Stack pile(uint64_t seed, int index) {
  const uint64_t h = mix(seed * 1000003ULL + static_cast<uint64_t>(index));
  piles::PileOptions o;
  o.blocks = 10 + static_cast<int>(h % 71);
  o.min_gap = (index % 3 == 0) ? 0.0 : (index % 3 == 1 ? 0.02 : 0.1);
  return piles::random_pile(h, o);
}

int Main(int argc, char** argv) {
  Flags flags("bricklayer-bench-vision", "Accuracy and speed of bricklayer-vision's detector on simulated frames.");
  flags.add("frames", "150", "frames per nuisance level and lighting at 640x480 (4 levels x 2 lightings)");
  flags.add("frames-720", "50", "frames per nuisance level and lighting at 1280x720 (0 = skip)");
  flags.add("seed", "1", "seed of the random piles and frames");
  flags.add_bool("calibrated", "also run a random distorted camera setup per level, detected through its true calibration");
  flags.add("dump", "", "write frames with a missed, extra or wrongly placed block (> 0.02) as PNG into this directory");
  flags.add_bool("line-stats", "print the relative depth of candidate lines on and off true end lines per level");
  if (!flags.parse(argc, argv)) return 0;
  const bool line_stats = flags.get_bool("line-stats");
  LineDepths line_depths[4][2];
  const int frames = static_cast<int>(flags.get_int("frames"));
  const int frames720 = static_cast<int>(flags.get_int("frames-720"));
  const uint64_t seed = static_cast<uint64_t>(flags.get_int("seed"));
  const std::string dump = flags.get("dump");
  if (frames < 1 || frames720 < 0) throw FlagError("--frames must be >= 1 and --frames-720 >= 0");
  if (!dump.empty()) std::filesystem::create_directories(dump);

  std::printf("| size | camera | level | light | frames | blocks | recall | precision | row errors | median dx | p95 dx | max dx | median ms | p99 ms |\n");
  std::printf("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n");
  Totals all_plain, all_light;
  std::vector<double> all_ms_640;
  struct Config {
    cv::Size size;
    bool calibrated;
    int frames;
  };
  std::vector<Config> configs = {{{640, 480}, false, frames}};
  if (frames720 > 0) configs.push_back({{1280, 720}, false, frames720});
  if (flags.get_bool("calibrated")) configs.push_back({{640, 480}, true, std::max(1, frames / 3)});
  for (const Config& config : configs) {
    for (int level = 0; level <= 3; ++level) {
      for (bool light : {false, true}) {
        const uint64_t setup_seed = seed * 17 + static_cast<uint64_t>(level);
        const simcam::CameraSetup cam = config.calibrated ? simcam::CameraSetup::random(setup_seed, config.size)
                                                          : simcam::CameraSetup::default_for(config.size);
        simcam::ProjectorSetup proj = config.calibrated ? simcam::ProjectorSetup::random(setup_seed) : simcam::ProjectorSetup{};
        // The default projector is mapped onto the 640x480 frame: the same projector on the same board seen
        // by a camera of more pixels covers proportionally more rectified pixels (unscaled, its light missed
        // the blocks of the 1280x720 frames).
        if (!config.calibrated) {
          const double k = config.size.width / 640.0;
          proj.projector_to_rectified = cv::Matx33d(k, 0, 0, 0, k, 0, 0, 0, 1) * proj.projector_to_rectified;
        }
        simcam::Renderer renderer(cam, proj);
        Detector detector(cam.board);
        // Through a calibration whenever the setup is not the default 640x480 one (the detector's built-in
        // camera -> projector mapping is that setup's; the exhibit always measures through its calibration).
        const bool through_calibration = config.calibrated || config.size != cv::Size(640, 480);
        if (through_calibration) detector.set_calibration(eval::true_calibration(cam, proj));
        const simcam::Nuisance nuisance = simcam::Nuisance::level(level);
        Totals t;
        for (int f = 0; f < config.frames; ++f) {
          const int index = level * 100000 + f;
          const core::Stack stack = pile(seed, index);
          const cv::Mat projection = light ? eval::red_blue_projection(stack, cam, proj) : cv::Mat();
          const simcam::Rendered r = renderer.render(stack, nuisance, light ? &projection : nullptr,
                                                     mix(seed + static_cast<uint64_t>(index) * 7 + (light ? 1 : 0)));
          if (light)
            detector.set_projector_image(projection, proj.size);
          else
            detector.clear_projector_image();
          detector.detect(r.bgr);  // the projector image changed: its leakage map is built here, not timed
          // Timed as bricklayer-vision spends it on a decoded frame: detection, then its publishing rules.
          const auto t0 = std::chrono::steady_clock::now();
          Detection d = detector.detect(r.bgr);
          make_publishable(d.blocks, detector.frame(), r.bgr.size());
          t.ms.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
          const eval::FrameScore s = eval::score(r.truth, d.blocks);
          ++t.frames;
          t.truth += s.truth, t.detected += s.detected, t.matched += s.matched, t.row_wrong += s.row_wrong;
          t.dx.insert(t.dx.end(), s.dx.begin(), s.dx.end());
          if (line_stats && config.size == cv::Size(640, 480) && !config.calibrated)
            collect_line_stats(cam, light ? &projection : nullptr, proj, r, line_depths[level][light]);
          const bool bad = s.matched != s.truth || s.matched != s.detected ||
                           (!s.dx.empty() && *std::max_element(s.dx.begin(), s.dx.end()) > 0.02);
          if (bad && !dump.empty()) {
            char name[256];
            std::snprintf(name, sizeof(name), "%s/%dx%d-%s-%s-%s-%05d.png", dump.c_str(), config.size.width,
                          config.size.height, config.calibrated ? "random" : "default", nuisance.name.c_str(),
                          light ? "light" : "plain", f);
            cv::imwrite(name, r.bgr);
            std::fprintf(stderr, "%s: truth %d detected %d matched %d row_wrong %d\n", name, s.truth, s.detected,
                         s.matched, s.row_wrong);
            for (const auto& tb : r.truth) std::fprintf(stderr, "  truth row %d x %.4f%s\n", tb.row, tb.x, tb.visible ? "" : " (partly outside)");
            for (const auto& db : d.blocks) std::fprintf(stderr, "  found row %d x %.4f conf %.2f\n", db.row, db.x, db.confidence);
            Detector explain(cam.board, [] { DetectorConfig c; c.keep_lines = true; return c; }());
            if (through_calibration) explain.set_calibration(eval::true_calibration(cam, proj));
            if (light) explain.set_projector_image(projection, proj.size);
            for (const auto& l : explain.detect(r.bgr).line_list)
              std::fprintf(stderr, "  line row %d x %.2f px (%.4f) depth %.3f\n", l.row, l.x_px,
                           cam.board.from_px_x(l.x_px), l.depth);
          }
        }
        const double recall = t.truth ? static_cast<double>(t.matched) / t.truth : 1.0;
        const double precision = t.detected ? static_cast<double>(t.matched) / t.detected : 1.0;
        std::printf("| %dx%d | %s | %s | %s | %d | %d | %.2f%% | %.2f%% | %d | %.4f | %.4f | %.4f | %.2f | %.2f |\n",
                    config.size.width, config.size.height,
                    config.calibrated ? "random+calib" : (through_calibration ? "default+calib" : "default"),
                    nuisance.name.c_str(), light ? "red/blue" : "off", t.frames, t.truth, 100 * recall,
                    100 * precision, t.row_wrong, percentile(t.dx, 0.5), percentile(t.dx, 0.95),
                    percentile(t.dx, 1.0), percentile(t.ms, 0.5), percentile(t.ms, 0.99));
        std::fflush(stdout);
        if (config.size == cv::Size(640, 480) && !config.calibrated) {
          Totals& all = light ? all_light : all_plain;
          all.frames += t.frames, all.truth += t.truth, all.detected += t.detected, all.matched += t.matched;
          all.row_wrong += t.row_wrong;
          all.dx.insert(all.dx.end(), t.dx.begin(), t.dx.end());
          all_ms_640.insert(all_ms_640.end(), t.ms.begin(), t.ms.end());
        }
      }
    }
  }
  for (bool light : {false, true}) {
    const Totals& a = light ? all_light : all_plain;
    std::printf("\n640x480 all levels, light %s: %d frames, %d blocks, recall %.3f%%, precision %.3f%%, row errors %d, "
                "median dx %.4f, p95 dx %.4f\n",
                light ? "red/blue" : "off", a.frames, a.truth, 100.0 * a.matched / std::max(1, a.truth),
                100.0 * a.matched / std::max(1, a.detected), a.row_wrong, percentile(a.dx, 0.5), percentile(a.dx, 0.95));
  }
  if (line_stats) {
    std::printf("\nCandidate line depth / frame median (640x480 default camera): percentiles 0 / 0.1 / 1 / 50 / 99\n");
    for (int level = 0; level <= 3; ++level)
      for (int light = 0; light <= 1; ++light)
        for (bool real : {true, false}) {
          const auto& v = real ? line_depths[level][light].real : line_depths[level][light].other;
          std::printf("%s %s %s: %zu lines, %.3f / %.3f / %.3f / %.3f / %.3f\n", simcam::Nuisance::level(level).name.c_str(),
                      light ? "red/blue" : "off", real ? "on a true line" : "elsewhere", v.size(), percentile(v, 0),
                      percentile(v, 0.001), percentile(v, 0.01), percentile(v, 0.5), percentile(v, 0.99));
        }
  }
  std::printf("640x480 detection time over %zu frames: median %.2f ms, p99 %.2f ms\n", all_ms_640.size(),
              percentile(all_ms_640, 0.5), percentile(all_ms_640, 0.99));
  return 0;
}

}  // namespace

int main(int argc, char** argv) { return bricklayer::run_main("bricklayer-bench-vision", &Main, argc, argv); }
