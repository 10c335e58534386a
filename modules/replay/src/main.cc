// bricklayer-replay: runs modules' real nodes on a recorded log, as fast as possible, and compares
// their outputs with the recorded ones (--check), with another configuration or another build's
// program (--diff), or rewrites a regression log's expected outputs (--update).
//
// Subscribes: nothing (reads log files). Publishes: nothing.
// Exit code: 0 when every compared output matches (and, for --diff, A and B agree); 1 on any mismatch
// (or difference); 3 when the log is damaged or incomplete (torn or truncated stretches, parts gone,
// events the logger could not keep), even with 0 mismatches; 2 on bad usage.
#include <malloc.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <map>
#include <memory>
#include <sstream>

#include "bricklayer/common/channels.h"
#include "bricklayer/common/flags.h"
#include "bricklayer/common/log.h"
#include "bricklayer/inspect/progress.h"
#include "bricklayer/launcher/process.h"
#include "bricklayer/replay/checker.h"
#include "bricklayer/replay/diff_report.h"
#include "bricklayer/replay/module_registry.h"
#include "bricklayer/replay/replayer.h"
#include "bricklayer/replay/time_arg.h"
#include "bricklayer/replay/video_render.h"
#include "bricklayer/node_config_t.hpp"
#include "bricklayer/runtime/codec.h"
#include "bricklayer/runtime/log_file.h"

namespace {

using namespace bricklayer;
using namespace bricklayer::replay;
namespace fs = std::filesystem;

// How far apart a recorded and a replayed output stamped at a loop tick may be and still pair: a live
// node's tick is late by at most its loop's period (projection: 1/60 s) plus the packets' wait.
constexpr int64_t kNearestToleranceUs = 50'000;

std::vector<std::string> split(const std::string& text, char sep) {
  std::vector<std::string> out;
  std::string item;
  std::istringstream in(text);
  while (std::getline(in, item, sep))
    if (!item.empty()) out.push_back(item);
  return out;
}

int64_t first_event_utime(const std::vector<std::string>& sources) {
  RecordingReader r(sources);
  runtime::LogEvent e;
  return r.next(e) ? e.utime : 0;
}

void print_modules(const Replayer& r, const std::string& label) {
  for (const auto& m : r.modules()) {
    std::cerr << "replay" << (label.empty() ? "" : " " + label) << ": " << m.name << " with "
              << (m.config_recorded ? "its recorded configuration" : "its defaults") << " " << m.config_json << "\n";
    for (const auto& n : m.notes) std::cerr << "replay: " << m.name << ": " << n << "\n";
  }
}

// The other build's replay: its outputs in a log file, read back in time order.
std::vector<std::tuple<int64_t, std::string, std::vector<uint8_t>>> run_program_b(const std::string& program,
                                                                                    const std::vector<std::string>& base_args) {
  const fs::path out = fs::temp_directory_path() / ("bricklayer-replay-b-" + std::to_string(::getpid()) + ".lcm");
  std::vector<std::string> argv = {program};
  argv.insert(argv.end(), base_args.begin(), base_args.end());
  argv.push_back("--record-outputs");
  argv.push_back(out.string());
  argv.push_back("--no-progress");
  launcher::SpawnOptions o;
  auto p = launcher::Process::spawn(argv, o);
  auto st = p.wait_for(std::chrono::hours(24));
  if (!st || st->signal != 0 || (st->code != 0 && st->code != 3))
    throw std::runtime_error("the other program (" + program + ") failed: " + (st ? st->describe() : "did not end"));
  std::vector<std::tuple<int64_t, std::string, std::vector<uint8_t>>> events;
  runtime::LogReader reader(out.string());
  runtime::LogEvent e;
  while (reader.next(e)) events.emplace_back(e.utime, e.channel, std::move(e.data));
  fs::remove(out);
  return events;
}

int Main(int argc, char** argv) {
  Flags flags("bricklayer-replay",
              "Runs modules' real nodes on a recorded log as fast as possible (each from the configuration it\n"
              "recorded on BL_CONFIG, --set overrides) and compares every output with the recorded one for the\n"
              "same input (--check: the first divergence and the differing fields; exit 1 on any mismatch, 3 on a\n"
              "damaged or incomplete log). --diff compares two replays (other settings with --set-b, or another\n"
              "build's bricklayer-replay with --program-b). --update rewrites a regression log's expected outputs.\n"
              "LOG: log files (parts) in order, or a recording's NAME.index. The last line of --check is\n"
              "\"N compared, M mismatches (...)\".");
  flags.add_positional_list("LOG", "log files in order, or one NAME.index");
  flags.add("module", "prediction",
            "the modules to replay, chained in this order: prediction, or vision,prediction (this build: " +
                replayable_names() + ")");
  flags.add_bool("check", "compare every output with the recorded one; exit 1 on any mismatch, 3 on damage");
  flags.add("set", "", "configuration overrides, comma-separated: annotator=paper or prediction.annotator=paper");
  flags.add("from", "", "start: seconds into the log (90), a time of day (14:32:05) or a date and time");
  flags.add("to", "", "end, as --from");
  flags.add("ignore", "", "more fields never compared, comma-separated: prediction_t.blocks[].accel, hint_t");
  flags.add_bool("diff", "compare two replays: A (--set) against B (--set plus --set-b, or --program-b)");
  flags.add("set-b", "", "--diff: B's overrides on top of A's");
  flags.add("program-b", "", "--diff: B is this bricklayer-replay (another build) with the same arguments");
  flags.add("record-outputs", "", "write the replayed outputs into this LCM log");
  flags.add_bool("update", "rewrite LOG: its recorded outputs become the replayed ones (a regression log)");
  flags.add("max-printed", "10", "mismatches and divergences printed (all are counted)");
  flags.add("video", "", "render OUT.mp4 (or .avi): camera frame and projector image side by side with the time, score,\n"
            "verdict and round; with --from/--to a moment (no module is replayed)");
  flags.add("speed", "1", "--video: 1 = recorded pace, 4 = four times faster");
  flags.add_bool("no-progress", "never print progress (it is printed on long runs: bytes, rate, time left)");
  flags.add("log-level", "info", "debug, info, warn or error");
  if (!flags.parse(argc, argv)) return 0;
  log::set_module("replay");
  log::set_level(log::parse_level(flags.get("log-level")));
  const std::vector<std::string> sources = flags.positional();
  const int64_t max_printed = flags.get_int("max-printed");
  if (max_printed < 0) throw FlagError("--max-printed must be >= 0");

  ReplayOptions options;
  options.modules = split(flags.get("module"), ',');
  options.sets = split(flags.get("set"), ',');
  const int64_t log_start = first_event_utime(sources);
  try {
    if (!flags.get("from").empty()) options.from_utime = parse_time_arg(flags.get("from"), log_start);
    if (!flags.get("to").empty()) options.to_utime = parse_time_arg(flags.get("to"), log_start);
  } catch (const std::invalid_argument& e) {
    throw FlagError(std::string("--from/--to: ") + e.what());
  }
  if (options.to_utime < options.from_utime) throw FlagError("--to is before --from");
  std::vector<std::string> ignored = run_to_run_fields();
  // The replayed modules' own run-to-run fields (module_registry.cc says why for each).
  for (const auto& name : options.modules)
    for (const auto& i : module_named(name).ignored)
      if (std::find(ignored.begin(), ignored.end(), i) == ignored.end()) ignored.push_back(i);
  for (const auto& i : split(flags.get("ignore"), ',')) ignored.push_back(i);
  const MessageDiff diff(ignored);
  // Outputs stamped at a loop tick: unpaired by key, they pair by nearest stamp time, compared
  // without their tick-dependent fields (module_registry.cc lists them per module).
  std::vector<std::string> nearest_channels, tick_fields, tick_inputs;
  for (const auto& name : options.modules) {
    const ModuleAdapter& a = module_named(name);
    if (!a.ticks_at_outputs) continue;
    nearest_channels.insert(nearest_channels.end(), a.compared.begin(), a.compared.end());
    tick_inputs.insert(tick_inputs.end(), a.tick_inputs.begin(), a.tick_inputs.end());
    for (const auto& f : a.tick_fields)
      if (std::find(tick_fields.begin(), tick_fields.end(), f) == tick_fields.end()) tick_fields.push_back(f);
  }
  std::vector<std::string> tick_ignored = ignored;
  tick_ignored.insert(tick_ignored.end(), tick_fields.begin(), tick_fields.end());
  const MessageDiff tick_diff(tick_ignored);
  if (flags.get_bool("update") && (sources.size() != 1 || fs::path(sources[0]).extension() == ".index"))
    throw FlagError("--update rewrites one log file (give exactly one part)");
  if (flags.get_bool("diff") && flags.get("set-b").empty() && flags.get("program-b").empty())
    throw FlagError("--diff needs --set-b or --program-b (what B changes)");

  const bool tty = ::isatty(2);
  inspect::Progress progress("bricklayer-replay", 0, false);
  auto show_progress = [&](std::unique_ptr<inspect::Progress>& p, const RecordingReader& reader) {
    if (!p) p = std::make_unique<inspect::Progress>("bricklayer-replay", static_cast<uint64_t>(reader.total_bytes()),
                                                    !flags.get_bool("no-progress"));
    p->update(static_cast<uint64_t>(reader.done_bytes()));
  };
  (void)tty;
  std::unique_ptr<inspect::Progress> bar;
  const auto t0 = std::chrono::steady_clock::now();

  // --video: the recorded moment as a video file.
  if (!flags.get("video").empty()) {
    VideoOptions vo;
    vo.path = flags.get("video");
    vo.speed = flags.get_double("speed");
    VideoRenderer video(vo);
    RecordingReader reader(sources, options.from_utime);
    runtime::LogEvent e;
    int64_t since = 0;
    while (reader.next(e)) {
      if (e.utime < options.from_utime) continue;
      if (e.utime > options.to_utime) break;
      video.observe(e);
      if (++since % 500 == 0) show_progress(bar, reader);
    }
    if (bar) bar->finish();
    const VideoSummary v = video.finish();
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    std::cout << "wrote " << vo.path << ": " << v.video_frames << " frames, " << v.duration_s << " s, from "
              << v.camera_frames << " camera frames (" << v.bad_frames << " undecodable) in " << seconds << " s" << std::endl;
    const auto damage = damage_report(reader, options.from_utime, options.to_utime, nullptr);
    for (const auto& d : damage) std::cout << "DAMAGED " << d << "\n";
    return damage.empty() ? 0 : 3;
  }

  // --diff: two replays in lockstep, compared with each other.
  if (flags.get_bool("diff")) {
    DiffReport report(diff, "A", "B", log_start, static_cast<size_t>(max_printed));
    std::cout << "A: " << (options.sets.empty() ? std::string("the recorded settings") : "--set " + flags.get("set")) << "\n"
              << "B: " << (flags.get("program-b").empty() ? "" : flags.get("program-b") + " ")
              << (flags.get("set-b").empty() ? std::string("the same settings") : "--set-b " + flags.get("set-b")) << "\n";
    std::vector<std::string> compared;
    auto is_compared = [&](const std::string& ch) { return std::find(compared.begin(), compared.end(), ch) != compared.end(); };
    auto side_sink = [&](int side) {
      return [&report, &is_compared, side](bool recorded, const std::string& ch, const std::vector<uint8_t>& bytes, int64_t utime) {
        if (!recorded && is_compared(ch)) report.add(side, ch, bytes, utime);
      };
    };
    Replayer a(sources, options, side_sink(0));
    compared = a.compared_channels();
    a.set_observer([](const runtime::LogEvent&) {});
    print_modules(a, "A");
    if (!flags.get("program-b").empty()) {
      std::vector<std::string> args = sources;
      for (const char* f : {"module", "set", "from", "to"})
        if (!flags.get(f).empty()) args.push_back("--" + std::string(f) + "=" + flags.get(f));
      if (!flags.get("set-b").empty()) {
        std::string sets = flags.get("set");
        sets += (sets.empty() ? "" : ",") + flags.get("set-b");
        args.back() = "--set=" + sets;
      }
      auto b_events = run_program_b(flags.get("program-b"), args);
      size_t next = 0;
      while (a.advance()) {
        while (next < b_events.size() && std::get<0>(b_events[next]) <= a.now_utime()) {
          auto& [t, ch, bytes] = b_events[next++];
          if (is_compared(ch)) report.add(1, ch, bytes, t);
        }
        report.advance(a.now_utime());
        show_progress(bar, a.reader());
      }
      for (; next < b_events.size(); ++next)
        if (is_compared(std::get<1>(b_events[next])))
          report.add(1, std::get<1>(b_events[next]), std::get<2>(b_events[next]), std::get<0>(b_events[next]));
    } else {
      ReplayOptions ob = options;
      for (const auto& s : split(flags.get("set-b"), ',')) ob.sets.push_back(s);
      Replayer b(sources, ob, side_sink(1));
      print_modules(b, "B");
      bool more_a = true, more_b = true;
      while (more_a || more_b) {
        if (more_a && (!more_b || a.now_utime() <= b.now_utime())) more_a = a.advance();
        else more_b = b.advance();
        report.advance(std::min(more_a ? a.now_utime() : INT64_MAX, more_b ? b.now_utime() : INT64_MAX));
        show_progress(bar, a.reader());
      }
    }
    report.finish();
    if (bar) bar->finish();
    report.print(std::cout);
    const auto damage = damage_report(a.reader(), options.from_utime, options.to_utime, nullptr);
    for (const auto& d : damage) std::cout << "DAMAGED " << d << "\n";
    std::cout << report.pairs() << " compared, " << report.differing() << " differ (" << report.only(0) << " only in A, "
              << report.only(1) << " only in B)" << std::endl;
    if (report.differing() > 0 || report.only(0) > 0 || report.only(1) > 0) return 1;
    return damage.empty() ? 0 : 3;
  }

  // --check / --update / --record-outputs: one replay against the log.
  Checker checker(diff, std::cout, log_start, static_cast<size_t>(max_printed));
  if (!nearest_channels.empty()) checker.set_nearest(nearest_channels, kNearestToleranceUs, tick_diff, tick_inputs);
  const bool check = flags.get_bool("check");
  std::unique_ptr<runtime::LogWriter> outputs, updated;
  if (!flags.get("record-outputs").empty()) outputs = std::make_unique<runtime::LogWriter>(flags.get("record-outputs"));
  const std::string update_tmp = sources[0] + ".updating";
  if (flags.get_bool("update")) updated = std::make_unique<runtime::LogWriter>(update_tmp);
  int64_t outputs_seen = 0;
  std::map<std::string, int64_t> recorded_on;  // recorded outputs per compared channel
  std::vector<std::string> compared;
  Replayer replayer(sources, options, [&](bool recorded, const std::string& ch, const std::vector<uint8_t>& bytes, int64_t utime) {
    const bool is_compared = std::find(compared.begin(), compared.end(), ch) != compared.end();
    if (!is_compared) return;
    if (recorded) {
      if (check) checker.recorded(ch, bytes, utime);
      ++recorded_on[ch];
      return;
    }
    ++outputs_seen;
    if (check) checker.replayed(ch, bytes, utime);
    if (outputs && !outputs->write(utime, ch, bytes.data(), bytes.size()))
      throw std::runtime_error("cannot write " + flags.get("record-outputs"));
    if (updated && !updated->write(utime, ch, bytes.data(), bytes.size())) throw std::runtime_error("cannot write " + update_tmp);
  });
  compared = replayer.compared_channels();
  const std::string config_channel = channel(kConfigChannel);
  replayer.set_observer([&](const runtime::LogEvent& e) {
    checker.observe(e);
    // The regression log keeps everything but the replayed modules' recorded outputs.
    if (!updated || replayer.is_recorded_output(e.channel, e.data)) return;
    std::vector<uint8_t> data = e.data;
    // A changed setting (--set) is meant too: the replayed modules' recorded configurations become
    // the ones they ran with, so the next check (without --set) runs them the same way.
    if (e.channel == config_channel && !options.sets.empty()) {
      if (auto c = runtime::decode<node_config_t>(e.data)) {
        for (const auto& m : replayer.modules())
          if (m.name == c->module && !m.config_json.empty()) {
            c->config_json = m.config_json;
            data = runtime::encode(*c);
          }
      }
    }
    if (!updated->write(e.utime, e.channel, data.data(), data.size())) throw std::runtime_error("cannot write " + update_tmp);
  });
  print_modules(replayer, "");
  std::vector<size_t> notes_printed;
  for (const auto& m : replayer.modules()) notes_printed.push_back(m.notes.size());
  if (check) {
    std::string list;
    for (const auto& i : ignored) list += (list.empty() ? "" : ", ") + i;
    std::cerr << "replay: compared on " << [&] {
      std::string c;
      for (const auto& ch : compared) c += (c.empty() ? "" : ", ") + ch;
      return c;
    }() << "; never compared (run-to-run): " << list << "\n";
    if (!nearest_channels.empty()) {
      std::string chs, fields;
      for (const auto& ch : nearest_channels) chs += (chs.empty() ? "" : ", ") + ch;
      for (const auto& f : tick_fields) fields += (fields.empty() ? "" : ", ") + f;
      std::cerr << "replay: stamped at a loop tick, so paired by nearest stamp time (within "
                << kNearestToleranceUs / 1000 << " ms) when not by key: " << chs
                << "; such pairs also leave out (tick-dependent): " << fields << "\n";
    }
  }
  int64_t since = 0;
  while (replayer.advance())
    if (++since % 2000 == 0) show_progress(bar, replayer.reader());
  if (bar) bar->finish();
  checker.finish();
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  const double span = static_cast<double>(replayer.last_utime() - replayer.first_utime()) / 1e6;
  std::cerr << "replay: " << replayer.events() << " events (" << span << " s of log) in " << seconds << " s";
  if (seconds > 0 && span > 0) std::cerr << ", " << span / seconds << " x real time";
  std::cerr << "\n";
  if (updated) {
    if (!updated->flush()) throw std::runtime_error("cannot write " + update_tmp);
    updated.reset();
    fs::rename(update_tmp, sources[0]);
    std::cout << "updated " << sources[0] << ": " << outputs_seen << " expected outputs of " << flags.get("module")
              << " rewritten" << std::endl;
  }
  const auto damage = damage_report(replayer.reader(), options.from_utime, options.to_utime, &checker.losses());
  for (const auto& d : damage) std::cout << "DAMAGED " << d << "\n";
  for (const auto& [module, errors] : replayer.node_errors())
    if (errors > 0) std::cout << "note: " << module << " counted " << errors << " errors (rejected inputs, failed computations)\n";
  // A module that started late says what its build changed only when it starts.
  for (size_t i = 0; i < replayer.modules().size(); ++i)
    for (size_t k = notes_printed[i]; k < replayer.modules()[i].notes.size(); ++k)
      std::cerr << "replay: " << replayer.modules()[i].name << ": " << replayer.modules()[i].notes[k] << "\n";
  // Say so when a channel paired nothing, rather than pass a check that compared nothing.
  if (check)
    for (const auto& [ch, n] : recorded_on)
      if (n > 0 && checker.counts().compared_by_channel.count(ch) == 0)
        std::cout << "note: none of the " << n << " recorded outputs on " << ch
                  << " paired with a replayed one, by key or by nearest time\n";
  if (!check) {
    std::cout << outputs_seen << " outputs replayed (" << replayer.events() << " log events)" << std::endl;
    return damage.empty() ? 0 : 3;
  }
  const CheckCounts& c = checker.counts();
  if (!checker.first_divergence().empty()) std::cout << "first divergence: " << checker.first_divergence() << "\n";
  if (!c.compared_by_channel.empty()) {
    std::cout << "compared per channel:";
    for (const auto& [ch, n] : c.compared_by_channel) {
      const auto m = c.mismatches_by_channel.find(ch);
      std::cout << " " << ch << " " << n << (m == c.mismatches_by_channel.end() ? "" : " (" + std::to_string(m->second) + " mismatches)");
    }
    std::cout << "\n";
  }
  if (c.nearest > 0) {
    std::cout << "paired by nearest time:";
    for (const auto& [ch, n] : c.nearest_by_channel) std::cout << " " << ch << " " << n;
    std::cout << " (replayed stamps within " << c.worst_nearest_offset_us / 1000.0 << " ms of the recorded ones)\n";
  }
  if (c.inputs_between > 0) {
    std::cout << "paired but not compared (live ticks: an input delivered between the two stamps or up to "
              << Checker::kInputInFlightUs / 1000 << " ms before the earlier):";
    for (const auto& [ch, n] : c.inputs_between_by_channel) std::cout << " " << ch << " " << n;
    std::cout << "\n";
  }
  if (c.tick_unpaired[0] + c.tick_unpaired[1] > 0)
    std::cout << "unpaired by time: " << c.tick_unpaired[0] << " recorded and " << c.tick_unpaired[1]
              << " replayed outputs stamped at a tick had no output about the same input on the other side within "
              << kNearestToleranceUs / 1000 << " ms (counted below, not compared)\n";
  std::cout << c.compared << " compared, " << c.mismatches << " mismatches (" << replayer.events() << " log events, "
            << outputs_seen << " outputs replayed, " << c.not_in_log << " not in the log, " << c.orphans
            << " recorded outputs without their input" << (damage.empty() ? "" : "; THE LOG IS DAMAGED OR INCOMPLETE")
            << ")" << std::endl;
  if (c.mismatches > 0) return 1;
  return damage.empty() ? 0 : 3;
}

}  // namespace

int main(int argc, char** argv) {
#ifdef __GLIBC__
  // A replay allocates and frees a decoded frame (about 1 MB) thirty times a second of log, on two threads
  // (frames/decode_ahead.h). glibc would hand each back to the kernel (mmap / munmap) and fault it in
  // again: 10% of a vision replay's time. Kept on the heap instead (a replay's memory is a few frames).
  mallopt(M_MMAP_THRESHOLD, 64 << 20);
  mallopt(M_TRIM_THRESHOLD, 256 << 20);
#endif
  return bricklayer::run_main("bricklayer-replay", &Main, argc, argv);
}
