// NETNS, real processes: hostile-but-decodable (and some undecodable) messages on every channel each
// process listens to. Every one must be a counted error in the process's heartbeat, the process must
// keep running (same pid, heartbeats continue). Covers vision, prediction, projection (headless),
// planner and calibrate --serve.
// A message a process does not use (a field it never reads, a command for another module) only has to
// be survived; such cases are marked unused() with the reason.
#include <catch2/catch.hpp>

#include <unistd.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <limits>

#include "bricklayer/calibration_t.hpp"
#include "bricklayer/command_t.hpp"
#include "bricklayer/image_t.hpp"
#include "bricklayer/common/channels.h"
#include "bricklayer/heartbeat_t.hpp"
#include "bricklayer/launcher/process.h"
#include "bricklayer/prediction_t.hpp"
#include "bricklayer/runtime/codec.h"
#include "bricklayer/runtime/lcm_bus.h"
#include "bricklayer/stack_t.hpp"
#include "harness/live_bus.h"
#include "harness/recorder.h"
#include "harness/scratch.h"

using namespace bricklayer;
using namespace std::chrono_literals;
namespace fs = std::filesystem;

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

struct Hostile {
  std::string what;
  std::string channel;
  std::vector<uint8_t> bytes;
  bool must_count = true;  // false: a field this process does not use; it must only survive it
};

Hostile unused(Hostile h) {
  h.must_count = false;
  return h;
}

stack_t good_stack(int n, int64_t frame) {
  stack_t s{};
  s.utime = 1000 + frame;
  s.frame_number = frame;
  s.block_length = 1.0;
  s.block_height = 1.0 / 3.0;
  s.table_edge = 0.0;
  s.status = stack_t::STATUS_OK;
  for (int i = 0; i < n; ++i) {
    block_t b{};
    b.id = i;
    b.row = i;
    b.x = -0.5 + 0.1 * i;
    b.confidence = 1.0;
    s.blocks.push_back(b);
  }
  s.num_blocks = n;
  return s;
}

// Overwrites the big-endian int32 that follows `offset` bytes of the encoded message (after the
// 8-byte fingerprint) -- a length field the sender lies about.
std::vector<uint8_t> patch_i32(std::vector<uint8_t> bytes, size_t offset, int32_t value) {
  const uint32_t v = static_cast<uint32_t>(value);
  const uint8_t be[4] = {uint8_t(v >> 24), uint8_t(v >> 16), uint8_t(v >> 8), uint8_t(v)};
  std::memcpy(bytes.data() + 8 + offset, be, 4);
  return bytes;
}

std::vector<Hostile> hostile_stacks() {
  const std::string ch = channel(kStackChannel);
  std::vector<Hostile> out;
  // num_blocks says 2^31-1 but three blocks follow: undecodable, must not allocate 2^31 blocks.
  // Offset of num_blocks: utime, frame_number (16) + 3 doubles (24) + status (1).
  out.push_back({"stack num_blocks 2^31-1 with 3 blocks", ch, runtime::encode(good_stack(3, 901))});
  out.back().bytes = patch_i32(out.back().bytes, 41, std::numeric_limits<int32_t>::max());
  out.push_back({"stack num_blocks -5", ch, patch_i32(runtime::encode(good_stack(3, 902)), 41, -5)});
  auto nan_x = good_stack(4, 903);
  nan_x.blocks[2].x = kNaN;
  out.push_back({"stack NaN x", ch, runtime::encode(nan_x)});
  auto neg_h = good_stack(3, 904);
  neg_h.block_height = -1.0;
  out.push_back({"stack negative block height", ch, runtime::encode(neg_h)});
  auto inf_edge = good_stack(3, 905);
  inf_edge.table_edge = std::numeric_limits<double>::infinity();
  out.push_back({"stack infinite table edge", ch, runtime::encode(inf_edge)});
  auto rows = good_stack(3, 906);
  rows.blocks[1].row = std::numeric_limits<int32_t>::max();
  out.push_back({"stack row 2^31-1", ch, runtime::encode(rows)});
  return out;
}

std::vector<Hostile> hostile_predictions() {
  const std::string ch = channel(kPredictionChannel);
  std::vector<Hostile> out;
  prediction_t p{};
  p.frame_number = 911;
  p.annotator = "exact";
  p.solver = "clp";
  p.balanced = true;
  p.num_blocks = 2;
  p.blocks.resize(2);
  // num_blocks is the last field before the blocks: its offset follows from the encoded sizes with two
  // blocks and with none, whatever fields precede it and however large a block entry is.
  const std::vector<uint8_t> encoded = runtime::encode(p);
  prediction_t none = p;
  none.num_blocks = 0;
  none.blocks.clear();
  const size_t blocks_bytes = encoded.size() - runtime::encode(none).size();
  const size_t num_blocks_offset = encoded.size() - 8 - blocks_bytes - 4;  // after the 8-byte fingerprint
  out.push_back({"prediction num_blocks 2^31-1 with 2 blocks", ch,
                 patch_i32(encoded, num_blocks_offset, std::numeric_limits<int32_t>::max())});
  auto nan = p;
  nan.frame_number = 912;
  nan.overhang = kNaN;
  out.push_back({"prediction NaN overhang", ch, runtime::encode(nan)});
  auto state = p;
  state.frame_number = 913;
  state.blocks[0].state = 77;
  out.push_back({"prediction block state 77", ch, runtime::encode(state)});
  auto status = p;
  status.frame_number = 914;
  status.status = -3;
  out.push_back({"prediction status -3", ch, runtime::encode(status)});
  return out;
}

image_t small_image(int64_t frame) {
  image_t m{};
  m.utime = 2000 + frame;
  m.frame_number = frame;
  m.width = 8;
  m.height = 8;
  m.format = image_t::FORMAT_GRAY8;
  m.source = "hostile";
  m.data.assign(64, 128);
  m.size = 64;
  return m;
}

std::vector<Hostile> hostile_images() {
  const std::string ch = channel(kImageChannel);
  std::vector<Hostile> out;
  auto huge = small_image(921);
  huge.width = 100000;
  huge.height = 100000;
  huge.format = image_t::FORMAT_BGR8;
  out.push_back({"image 100000x100000 with 64 bytes", ch, runtime::encode(huge)});
  auto overflow = small_image(922);
  overflow.width = 65536;
  overflow.height = 65536;  // width*height wraps to 0 in 32 bits
  out.push_back({"image 65536x65536 (32-bit product wraps)", ch, runtime::encode(overflow)});
  auto negative = small_image(923);
  negative.width = -8;
  out.push_back({"image negative width", ch, runtime::encode(negative)});
  auto format = small_image(924);
  format.format = 99;
  out.push_back({"image unknown format", ch, runtime::encode(format)});
  auto png = small_image(925);
  png.format = image_t::FORMAT_PNG;  // 64 bytes of 0x80 are no PNG
  out.push_back({"image PNG that is not a PNG", ch, runtime::encode(png)});
  // size offset: utime, frame (16) + width, height, format (12) + source string (4 + 8).
  out.push_back({"image size -1", ch, patch_i32(runtime::encode(small_image(926)), 40, -1)});
  return out;
}

std::vector<Hostile> hostile_calibrations() {
  const std::string ch = channel(kCalibrationChannel);
  std::vector<Hostile> out;
  calibration_t c{};
  c.camera_width = 640;
  c.camera_height = 480;
  c.projector_width = 1024;
  c.projector_height = 768;
  c.camera_matrix[0] = kNaN;
  out.push_back({"calibration NaN focal length", ch, runtime::encode(c)});
  calibration_t n{};
  n.camera_width = -640;
  n.camera_height = 1 << 30;
  out.push_back({"calibration negative / huge image size", ch, runtime::encode(n)});
  return out;
}

std::vector<Hostile> hostile_commands() {
  const std::string ch = channel(kCommandChannel);
  std::vector<Hostile> out;
  command_t c{};
  c.command = command_t::SHOW_PATTERN;
  c.pattern = 12345;
  c.index = -7;
  c.red = -300;
  c.sequence = 931;
  out.push_back({"command unknown pattern, negative index and colour", ch, runtime::encode(c)});
  command_t u{};
  u.command = 999;
  u.sequence = 932;
  out.push_back({"command 999", ch, runtime::encode(u)});
  return out;
}

struct Case {
  std::string module;
  std::vector<std::string> argv;
  std::vector<std::vector<Hostile>> inputs;
  std::string cwd = "";
};

void run_case(const Case& c) {
  INFO("module " << c.module);
  launcher::SpawnOptions opts;
  opts.env = {std::string("LCM_DEFAULT_URL=") + harness::kLiveUrl, "SDL_VIDEODRIVER=offscreen", "SDL_AUDIODRIVER=dummy"};
  opts.stdout_path = fs::temp_directory_path() / ("bricklayer-hostile-" + c.module + "-" + std::to_string(::getpid()) + ".log");
  opts.merge_stderr = true;
  opts.cwd = c.cwd;
  auto proc = launcher::Process::spawn(c.argv, opts);
  runtime::LcmBus bus(harness::kLiveUrl);
  REQUIRE(bus.open());
  harness::Recorder rec = harness::Recorder::live(bus, {channel(kHeartbeatChannel)});
  REQUIRE(rec.wait_for_heartbeat(c.module, [&](const heartbeat_t& h) { return h.pid == proc.pid(); }, 15s));
  rec.pump_for(300ms);  // start-up settled (a calibration published at start, first frames)
  const auto hb = rec.last_heartbeat(c.module);
  REQUIRE(hb);
  // One message at a time, each followed by the next heartbeat (sent at least 100 ms after it, so the
  // message has been handled): its error counter must have grown by at least one.
  int64_t errors = hb->errors;
  for (const auto& group : c.inputs) {
    for (const auto& h : group) {
      INFO(h.what);
      rec.pump_for(20ms);
      rec.clear();
      const int64_t sent_at = bus.now_utime();
      harness::publish_bytes(bus, h.channel, h.bytes);
      heartbeat_t after{};
      REQUIRE(rec.wait_until([&] {
        for (const auto& m : rec.messages()) {
          if (m.channel != channel(kHeartbeatChannel) || m.utime <= sent_at + 100'000) continue;
          const auto beat = runtime::decode<heartbeat_t>(m.bytes);
          if (beat && beat->module == c.module) {
            after = *beat;
            return true;
          }
        }
        return false;
      }, 5s));
      REQUIRE(proc.running());
      CHECK(after.pid == proc.pid());
      if (h.must_count) CHECK(after.errors > errors);
      errors = after.errors;
    }
  }
  REQUIRE(proc.running());
  proc.stop(5s);
}

}  // namespace

TEST_CASE("prediction counts every hostile stack as an error and keeps running") {
  run_case({"prediction", {harness::program_path("bricklayer-prediction"), "--log-level", "error"}, {hostile_stacks()}});
}

TEST_CASE("vision counts every hostile frame and calibration as an error and keeps running") {
  run_case({"vision", {harness::program_path("bricklayer-vision"), "--log-level", "error"}, {hostile_images(), hostile_calibrations()}});
}

TEST_CASE("projection counts every hostile stack, prediction, calibration and command it uses as an error") {
  // Projection computes the overhang from the stack, shows any non-OK status as "no verdict", and
  // leaves command codes it does not know to other modules: those three only have to be survived.
  auto predictions = hostile_predictions();
  for (auto& h : predictions)
    if (h.what == "prediction NaN overhang" || h.what == "prediction status -3") h = unused(h);
  auto commands = hostile_commands();
  commands[1] = unused(commands[1]);
  run_case({"projection",
            {harness::program_path("bricklayer-projection"), "--headless", "--log-level", "error"},
            {hostile_stacks(), predictions, hostile_calibrations(), commands}});
}

TEST_CASE("planner counts every hostile stack it plans with as an error and survives the rest") {
  // The planner only uses a prediction that answers the stack it holds (these answer none). It keeps a
  // stack with a block in row 2^31-1 without complaint (prediction rejects it); a hint is then asked
  // for on that stack, which must not crash or allocate rows up to 2^31.
  auto stacks = hostile_stacks();
  for (auto& h : stacks)
    if (h.what == "stack row 2^31-1") h = unused(h);
  command_t hint{};
  hint.command = command_t::REQUEST_HINT;
  hint.sequence = 940;
  stacks.push_back(unused({"REQUEST_HINT after the row 2^31-1 stack", channel(kCommandChannel), runtime::encode(hint)}));
  auto predictions = hostile_predictions();
  for (auto& h : predictions) h = unused(h);
  run_case({"planner", {harness::program_path("bricklayer-planner"), "--log-level", "error"}, {stacks, predictions}});
}

TEST_CASE("calibrate --serve survives hostile frames, commands and stacks and counts those it uses") {
  const std::string dir = fs::temp_directory_path() / ("bricklayer-hostile-cal-" + std::to_string(::getpid()));
  fs::create_directories(dir);
  {
    launcher::SpawnOptions o;
    o.cwd = dir;
    auto w = launcher::Process::spawn({harness::program_path("bricklayer-calibrate"), "--write-default", "--output=calibration.json"}, o);
    auto st = w.wait_for(10s);
    REQUIRE(st);
    REQUIRE(st->clean());
  }
  // Serving, it reads frames only during a self-check, stacks only for "is the board empty", and
  // ignores commands other than SELF_CHECK: it must survive all of them; the undecodable ones
  // (lying length fields) are counted errors like everywhere.
  std::vector<std::vector<Hostile>> inputs = {hostile_images(), hostile_commands(), hostile_stacks()};
  for (auto& group : inputs)
    for (auto& h : group)
      if (h.what.find("num_blocks") == std::string::npos && h.what.find("size -1") == std::string::npos) h = unused(h);
  Case c{"calibrate", {harness::program_path("bricklayer-calibrate"), "--serve", "--log-level", "error"}, inputs, dir};
  run_case(c);
  fs::remove_all(dir);
}
