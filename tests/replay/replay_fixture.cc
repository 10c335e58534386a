#include "replay_fixture.h"

#include "bricklayer/command_t.hpp"
#include "bricklayer/common/channels.h"
#include "bricklayer/planner/planner_node.h"
#include "bricklayer/prediction/prediction_node.h"
#include "bricklayer/prediction/sample_stacks.h"
#include "bricklayer/runtime/config.h"
#include "bricklayer/runtime/log_file.h"
#include "bricklayer/simcam/simcam_node.h"
#include "bricklayer/vision/vision_node.h"
#include "harness/rig.h"

namespace bricklayer::test {

namespace {
void write_log(const std::string& path, const harness::Recorder& rec, runtime::LogWriter& w) {
  for (const auto& m : rec.messages())
    if (!w.write(m.utime, m.channel, m.bytes.data(), m.bytes.size())) throw std::runtime_error("cannot write " + path);
  w.flush();
}
}  // namespace

int64_t record_run(const std::string& path, const std::vector<stack_t>& stacks, const RunOptions& o) {
  const int64_t start = stacks.empty() ? runtime::InProcessBus::kDefaultStartUtime : stacks.front().utime;
  harness::Rig rig(1000, start);
  auto& p = rig.add<prediction::PredictionNode>(o.prediction);
  p.set_config(prediction::PredictionNode::kProgram, runtime::to_json(o.prediction).dump());
  if (o.planner) {
    auto& pl = rig.add<planner::PlannerNode>(planner::PlannerConfig{});
    pl.set_config(planner::PlannerNode::kProgram, runtime::to_json(planner::PlannerConfig{}).dump());
  }
  auto& rec = rig.record({".*"});
  int i = 0;
  for (const stack_t& s : stacks) {
    if (s.utime > rig.now()) rig.run_for(std::chrono::microseconds(s.utime - rig.now()));
    rig.publish(channel(kStackChannel), s);
    if (o.hint_every > 0 && ++i % o.hint_every == 0) {
      command_t c{};
      c.utime = rig.now();
      c.command = command_t::REQUEST_HINT;
      rig.publish(channel(kCommandChannel), c);
    }
    rig.step();
  }
  rig.run_for(std::chrono::milliseconds(200));
  runtime::LogWriter w(path);
  write_log(path, rec, w);
  return w.events();
}

int64_t record_camera_run(const std::string& path, const std::string& scenario, int frames) {
  harness::Rig rig(1000);
  simcam::SimcamConfig camera;
  camera.scenario = scenario;
  camera.frames = frames;
  camera.no_projector = true;
  rig.add<simcam::SimcamNode>(camera);
  auto& v = rig.add<vision::VisionNode>(vision::VisionConfig{});
  v.set_config(vision::VisionNode::kProgram, runtime::to_json(vision::VisionConfig{}).dump());
  auto& p = rig.add<prediction::PredictionNode>(prediction::PredictionConfig{});
  p.set_config(prediction::PredictionNode::kProgram, runtime::to_json(prediction::PredictionConfig{}).dump());
  auto& rec = rig.record({".*"});
  rig.run_for(std::chrono::microseconds(static_cast<int64_t>(frames) * 33'334 + 300'000));
  runtime::LogWriter w(path);
  write_log(path, rec, w);
  return w.events();
}

std::vector<stack_t> demo_stacks(int n, int64_t start) {
  std::vector<stack_t> out;
  for (int f = 0; f < n; ++f) {
    // Piles of 2..13 blocks, a new pile every 10 frames: the same pile measured repeatedly, as vision does.
    stack_t s = prediction::sample_stack(2 + (f / 10) % 12, static_cast<uint32_t>(f / 10), start + f * 33'333, f);
    out.push_back(std::move(s));
  }
  return out;
}

std::vector<stack_t> figure15_stacks(int64_t start) {
  // Ids 0 (bottom), 1 (middle), 2 (upper); x as in launch/stacks/figure15-*.json.
  const double cases[3][3] = {{-1.2, -1.1, -0.5}, {-1.2, -0.6, 0.2}, {-1.2, -0.6, -0.7}};
  std::vector<stack_t> out;
  for (int c = 0; c < 3; ++c) {
    for (int k = 0; k < 10; ++k) {  // each case seen for ten frames
      const int f = c * 10 + k;
      stack_t s{};
      s.utime = start + f * 33'333;
      s.frame_number = f;
      s.block_length = 1.0;
      s.block_height = 1.0 / 3.0;
      s.table_edge = 0.0;
      s.status = stack_t::STATUS_OK;
      for (int b = 0; b < 3; ++b) {
        block_t bl{};
        bl.id = b;
        bl.row = b;
        bl.x = cases[c][b];
        bl.confidence = 1.0;
        s.blocks.push_back(bl);
      }
      s.num_blocks = 3;
      out.push_back(s);
    }
  }
  return out;
}

}  // namespace bricklayer::test
