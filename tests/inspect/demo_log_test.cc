// bricklayer-export and bricklayer-report on the demo log the fixture recorded with the real processes
// (record_demo_log.cc): every message is in the CSV and JSON-lines files; every MCAP message reads back
// through Foxglove's reference readers and equals the log's message decoded by lcm-gen's classes;
// pandas reads the CSVs as they are and recomputes the report's numbers; the page loads in Debian's
// Chromium with no console error and plots that show data; damaged logs give a clear error after
// everything readable was written.
#include <catch2/catch.hpp>

#include <lcm/lcm-cpp.hpp>
#include <openssl/sha.h>

#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <nlohmann/json.hpp>
#include <sstream>

#include "bricklayer/calibration_t.hpp"
#include "bricklayer/collapse_preview_t.hpp"
#include "bricklayer/command_t.hpp"
#include "bricklayer/heartbeat_t.hpp"
#include "bricklayer/hint_t.hpp"
#include "bricklayer/host_state_t.hpp"
#include "bricklayer/node_config_t.hpp"
#include "bricklayer/study_answer_t.hpp"
#include "bricklayer/study_command_t.hpp"
#include "bricklayer/study_problem_t.hpp"
#include "bricklayer/study_session_t.hpp"
#include "bricklayer/study_trial_t.hpp"
#include "bricklayer/image_t.hpp"
#include "bricklayer/launcher/process.h"
#include "bricklayer/prediction_t.hpp"
#include "bricklayer/projector_state_t.hpp"
#include "bricklayer/round_t.hpp"
#include "bricklayer/stack_t.hpp"
#include "bricklayer/timing_t.hpp"

using namespace bricklayer;
using nlohmann::json;
namespace fs = std::filesystem;

namespace {

const fs::path kDemoLog = fs::path(BRICKLAYER_BINARY_DIR) / "test-output/inspect/demo/demo.lcmlog";
const std::string kBin = std::string(BRICKLAYER_BINARY_DIR) + "/bin/";
const std::string kJs = std::string(BRICKLAYER_SOURCE_DIR) + "/modules/inspect/js/";
const std::string kNode = launcher::find_program("node", "", {});  // on PATH (Debian's, or the machine's)

fs::path output(const std::string& name) {
  fs::path p = fs::path(BRICKLAYER_BINARY_DIR) / "test-output/inspect" / name;
  fs::remove_all(p);
  fs::create_directories(p);
  return p;
}

std::string slurp(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

struct Run {
  int code = -1;
  std::string out, err;
};

// Runs a program to its end (at most 120 s), its output captured.
Run run(const std::vector<std::string>& argv, const fs::path& dir) {
  launcher::SpawnOptions o;
  o.stdout_path = (dir / "run.out").string();
  o.stderr_path = (dir / "run.err").string();
  auto p = launcher::Process::spawn(argv, o);
  auto status = p.wait_for(std::chrono::seconds(120));
  REQUIRE(status);
  Run r;
  r.code = status->signal ? -status->signal : status->code;
  r.out = slurp(dir / "run.out");
  r.err = slurp(dir / "run.err");
  return r;
}

std::string sha256(const std::vector<uint8_t>& bytes) {
  unsigned char digest[SHA256_DIGEST_LENGTH];
  SHA256(bytes.data(), bytes.size(), digest);
  std::string hex;
  char buf[3];
  for (unsigned char c : digest) {
    std::snprintf(buf, sizeof buf, "%02x", c);
    hex += buf;
  }
  return hex;
}

struct Event {
  std::string channel;
  int64_t timestamp;
  std::vector<uint8_t> data;
  int64_t fingerprint() const {
    int64_t v = 0;
    for (size_t i = 0; i < 8 && i < data.size(); ++i) v = (v << 8) | data[i];
    return v;
  }
};

// The log as LCM's own reader (lcm::LogFile) sees it: independent of the exporters' reader.
std::vector<Event> lcm_events(const fs::path& log) {
  lcm::LogFile f(log.string(), "r");
  REQUIRE(f.good());
  std::vector<Event> out;
  while (const lcm::LogEvent* e = f.readNextEvent()) {
    const auto* p = static_cast<const uint8_t*>(e->data);
    out.push_back({e->channel, e->timestamp, std::vector<uint8_t>(p, p + e->datalen)});
  }
  return out;
}

template <typename T>
bool decode(const Event& e, T& msg) {
  return e.fingerprint() == T::getHash() && msg.decode(e.data.data(), 0, static_cast<int>(e.data.size())) == static_cast<int>(e.data.size());
}

// True when lcm-gen generated a class for the message's type (its fingerprint is one of theirs).
bool generated_type(const Event& e) {
  static const std::vector<int64_t> hashes = {
      image_t::getHash(), stack_t::getHash(), prediction_t::getHash(), timing_t::getHash(), heartbeat_t::getHash(),
      command_t::getHash(), calibration_t::getHash(), round_t::getHash(), projector_state_t::getHash(),
      collapse_preview_t::getHash(), hint_t::getHash(), node_config_t::getHash(), study_session_t::getHash(),
      study_trial_t::getHash(), study_problem_t::getHash(), study_answer_t::getHash(), study_command_t::getHash(),
      host_state_t::getHash()};
  return std::find(hashes.begin(), hashes.end(), e.fingerprint()) != hashes.end();
}

std::vector<std::string> lines(const std::string& text) {
  std::vector<std::string> out;
  std::stringstream s(text);
  for (std::string l; std::getline(s, l);) out.push_back(l);
  return out;
}

}  // namespace

TEST_CASE("the CSV and JSON-lines exports hold every message of the recorded demo log") {
  REQUIRE(fs::exists(kDemoLog));
  fs::path dir = output("export_files");
  Run r = run({kBin + "bricklayer-export", kDemoLog.string(), "--csv", (dir / "csv").string(), "--jsonl", (dir / "jsonl").string()}, dir);
  INFO(r.err);
  REQUIRE(r.code == 0);

  // Expected messages and rows per channel, from lcm-gen's classes: one row per block (stacks,
  // predictions), per named value (heartbeats), per module (host states), else one; an empty array still
  // one row.
  std::map<std::string, uint64_t> expected_messages, expected_rows;
  uint64_t undecoded = 0;
  for (const Event& e : lcm_events(kDemoLog)) {
    stack_t s;
    prediction_t p;
    heartbeat_t h;
    host_state_t hs;
    uint64_t rows = 1;
    if (decode(e, s)) rows = std::max<uint64_t>(1, s.blocks.size());
    else if (decode(e, p)) rows = std::max<uint64_t>(1, p.blocks.size());
    else if (decode(e, h)) rows = std::max<uint64_t>(1, h.values.size());
    else if (decode(e, hs)) rows = std::max<uint64_t>(1, hs.modules.size());
    else if (!generated_type(e)) {
      ++undecoded;
      continue;
    }
    expected_messages[e.channel]++;
    expected_rows[e.channel] += rows;
  }
  REQUIRE(expected_messages.size() >= 8);
  CHECK(expected_messages.at("BL_STACK") > 50);
  CHECK(undecoded >= 3);  // the three malformed stacks (and LCM's self-test messages)
  CHECK(expected_messages.at("BL_COMMAND") == 3);  // the fixture's START, RESET, START

  std::map<std::string, std::pair<uint64_t, uint64_t>> index;  // channel -> messages, rows
  std::string index_text = slurp(dir / "csv/index.csv");
  for (const auto& line : lines(index_text)) {
    if (line.rfind("file,", 0) == 0) continue;
    std::vector<std::string> cells;
    std::stringstream s(line);
    for (std::string c; std::getline(s, c, ',');) cells.push_back(c);
    REQUIRE(cells.size() == 5);
    if (cells[0] == "undecoded.csv") {
      CHECK(std::stoull(cells[3]) == undecoded);
      continue;
    }
    index[cells[1]] = {std::stoull(cells[3]), std::stoull(cells[4])};
    // The file holds a header and exactly that many rows; the JSON-lines file one line per message.
    CHECK(lines(slurp(dir / "csv" / cells[0])).size() == std::stoull(cells[4]) + 1);
    fs::path jsonl = dir / "jsonl" / (cells[0].substr(0, cells[0].size() - 4) + ".jsonl");
    auto jl = lines(slurp(jsonl));
    CHECK(jl.size() == std::stoull(cells[3]));
    CHECK(json::parse(jl.front()).at("channel") == cells[1]);
  }
  for (const auto& [channel, n] : expected_messages) {
    INFO(channel);
    REQUIRE(index.count(channel));
    CHECK(index.at(channel).first == n);
    CHECK(index.at(channel).second == expected_rows.at(channel));
  }
  CHECK(index.size() == expected_messages.size());
}

TEST_CASE("pandas reads every CSV as it is and recomputes the report's numbers from them") {
  REQUIRE(fs::exists(kDemoLog));
  fs::path dir = output("report_vs_csv");
  Run e = run({kBin + "bricklayer-export", kDemoLog.string(), "--csv", (dir / "csv").string()}, dir);
  REQUIRE(e.code == 0);
  Run r = run({kBin + "bricklayer-report", kDemoLog.string(), "--out", (dir / "report").string()}, dir);
  INFO(r.err);
  REQUIRE(r.code == 0);
  json report = json::parse(slurp(dir / "report/report.json"));
  // The demo did what the fixture made it do: two rounds, piles that turned red (at least one fell),
  // a restart and the errors of the malformed stacks.
  CHECK(report.at("rounds").size() == 2);
  CHECK(report.at("red_summary").at("episodes").get<int>() >= 2);
  CHECK(report.at("red_summary").at("fell").get<int>() >= 1);
  CHECK(report.at("latency_us").at("samples").get<int>() > 20);
  uint64_t restarts = 0, errors = 0;
  for (const auto& m : report.at("modules")) {
    restarts += m.at("restarts_seen").get<uint64_t>();
    errors += m.at("errors").get<uint64_t>();
  }
  CHECK(restarts == 1);
  CHECK(errors >= 3);
  CHECK(report.at("disk").at("bytes").get<uint64_t>() == fs::file_size(kDemoLog));
  // The fixture's study sessions: two conditions counted, the aborted session left out.
  REQUIRE(report.contains("study"));
  CHECK(report.at("study").at("rows").size() == 2);
  CHECK(report.at("study").at("excluded").size() == 1);

  Run check = run({"/usr/bin/python3", std::string(BRICKLAYER_SOURCE_DIR) + "/tests/inspect/report_from_csv.py",
                   (dir / "csv").string(), (dir / "report/report.json").string()},
                  dir);
  INFO(check.out << check.err);
  CHECK(check.code == 0);
  CHECK_THAT(check.out, Catch::Contains(" differ") && Catch::Contains(", 0 differ"));

  // The same script sees a report that is one off.
  report["rounds"][1]["max_score_points"] = report["rounds"][1]["max_score_points"].get<int>() + 1;
  std::ofstream(dir / "altered.json") << report.dump();
  Run altered = run({"/usr/bin/python3", std::string(BRICKLAYER_SOURCE_DIR) + "/tests/inspect/report_from_csv.py",
                     (dir / "csv").string(), (dir / "altered.json").string()},
                    dir);
  CHECK(altered.code == 1);
  CHECK_THAT(altered.out, Catch::Contains("round MAX"));
}

TEST_CASE("every MCAP message round-trips through the reference reader") {
  REQUIRE(fs::exists(kDemoLog));
  fs::path dir = output("mcap");
  fs::path mcap = dir / "demo.mcap";
  Run e = run({kBin + "bricklayer-export", kDemoLog.string(), "--mcap", mcap.string()}, dir);
  INFO(e.err);
  REQUIRE(e.code == 0);
  Run check = run({kNode, kJs + "mcap_check.mjs", mcap.string(), "--dump", (dir / "dump.jsonl").string()}, dir);
  INFO(check.err);
  REQUIRE(check.code == 0);
  json summary = json::parse(check.out);

  // What the log holds, decoded by lcm-gen's classes, in log order per topic.
  std::map<std::string, std::vector<json>> expected;
  for (const Event& ev : lcm_events(kDemoLog)) {
    json m = {{"publish_time_ns", std::to_string(ev.timestamp) + "000"}};
    stack_t s;
    prediction_t p;
    heartbeat_t h;
    timing_t t;
    round_t ro;
    image_t im;
    projector_state_t ps;
    if (decode(ev, s)) {
      m["log_time_ns"] = std::to_string(s.utime) + "000";
      json blocks = json::array();
      for (const auto& b : s.blocks) blocks.push_back({{"id", b.id}, {"x", b.x}, {"corner_v3", b.corner_v[3]}});
      m["fields"] = {{"frame_number", s.frame_number}, {"blocks", blocks}};
    } else if (decode(ev, p)) {
      m["log_time_ns"] = std::to_string(p.utime) + "000";
      json states = json::array();
      for (const auto& b : p.blocks) states.push_back(b.state);
      m["fields"] = {{"score", p.score}, {"balanced", p.balanced != 0}, {"overhang", p.overhang}, {"states", states}};
    } else if (decode(ev, h)) {
      m["log_time_ns"] = std::to_string(h.utime) + "000";
      m["fields"] = {{"module", h.module}, {"errors", h.errors}, {"restarts", h.restarts}, {"values", h.values}};
    } else if (decode(ev, t)) {
      m["log_time_ns"] = std::to_string(t.utime) + "000";
      m["fields"] = {{"stage", t.stage}, {"elapsed_us", t.elapsed_us}, {"received_utime", t.received_utime}};
    } else if (decode(ev, ro)) {
      m["log_time_ns"] = std::to_string(ro.utime) + "000";
      m["fields"] = {{"state", ro.state}, {"max_score", ro.max_score}, {"remaining_ms", ro.remaining_ms}};
    } else if (decode(ev, im)) {
      m["log_time_ns"] = std::to_string(im.utime) + "000";
      m["fields"] = {{"frame_number", im.frame_number}, {"size", im.size}};
      expected[ev.channel + "/image"].push_back(
          {{"log_time_ns", std::to_string(im.utime) + "000"}, {"publish_time_ns", std::to_string(ev.timestamp) + "000"},
           {"image", {{"format", im.format == image_t::FORMAT_JPEG ? "jpeg" : "png"}, {"sha256", sha256(im.data)}, {"bytes", im.data.size()}}}});
    } else if (decode(ev, ps)) {
      m["log_time_ns"] = std::to_string(ps.utime) + "000";
      m["fields"] = {{"frame_number", ps.frame_number}, {"mode", ps.mode}};
      expected[ev.channel + "/image"].push_back(
          {{"log_time_ns", std::to_string(ps.image.utime) + "000"}, {"publish_time_ns", std::to_string(ev.timestamp) + "000"},
           {"image", {{"format", "png"}, {"sha256", sha256(ps.image.data)}, {"bytes", ps.image.data.size()}}}});
    } else if (command_t c; decode(ev, c)) {
      // The fixture leaves utime 0, as a tool may: the receive time stands in for it.
      m["log_time_ns"] = c.utime > 0 ? std::to_string(c.utime) + "000" : m["publish_time_ns"].get<std::string>();
      m["fields"] = {{"command", c.command}, {"sequence", c.sequence}, {"argument", c.argument}};
    } else if (node_config_t nc; decode(ev, nc)) {
      m["log_time_ns"] = nc.utime > 0 ? std::to_string(nc.utime) + "000" : m["publish_time_ns"].get<std::string>();
      m["fields"] = {{"module", nc.module}};
    } else if (generated_type(ev) && ev.data.size() >= 16) {
      // Another generated type (the study messages): every one starts with its int64 utime.
      int64_t utime = 0;
      for (size_t i = 8; i < 16; ++i) utime = (utime << 8) | ev.data[i];
      m["log_time_ns"] = utime > 0 ? std::to_string(utime) + "000" : m["publish_time_ns"].get<std::string>();
      m["fields"] = {{"utime", utime}};
    } else {
      m["log_time_ns"] = m["publish_time_ns"];
      m["undecoded_bytes"] = ev.data.size();
      expected[ev.channel + "|undecoded"].push_back(m);  // a channel of its own (its own schema and sequence)
      continue;
    }
    expected[ev.channel].push_back(m);
  }
  std::map<std::string, std::vector<json>> read;  // topic -> messages in sequence order
  for (const auto& line : lines(slurp(dir / "dump.jsonl"))) {
    json j = json::parse(line);
    read[j.at("topic").get<std::string>() + (j.at("schema") == "bricklayer.undecoded" ? "|undecoded" : "")].push_back(j);
  }
  uint64_t total = 0;
  for (auto& [topic, msgs] : expected) {
    INFO(topic);
    REQUIRE(read.count(topic));
    auto& got = read.at(topic);
    std::stable_sort(got.begin(), got.end(), [](const json& a, const json& b) { return a.at("sequence") < b.at("sequence"); });
    REQUIRE(got.size() == msgs.size());
    for (size_t i = 0; i < msgs.size(); ++i) {
      const json& want = msgs[i];
      const json& have = got[i];
      const json& m = have.at("message");
      CHECK(have.at("sequence") == i);
      CHECK(have.at("log_time_ns") == want.at("log_time_ns"));
      CHECK(have.at("publish_time_ns") == want.at("publish_time_ns"));
      if (want.contains("image")) {
        CHECK(have.at("schema") == "foxglove.CompressedImage");
        CHECK(m.at("format") == want["image"]["format"]);
        CHECK(m.at("data_sha256") == want["image"]["sha256"]);
        CHECK(m.at("data_bytes") == want["image"]["bytes"]);
      } else if (want.contains("fields")) {
        const json& f = want.at("fields");
        for (auto it = f.begin(); it != f.end(); ++it) {
          if (it.key() == "blocks") {
            REQUIRE(m.at("blocks").size() == it->size());
            for (size_t b = 0; b < it->size(); ++b) {
              CHECK(m["blocks"][b]["id"] == (*it)[b]["id"]);
              CHECK(m["blocks"][b]["x"].get<double>() == (*it)[b]["x"].get<double>());
              CHECK(m["blocks"][b]["corner_v"][3].get<double>() == (*it)[b]["corner_v3"].get<double>());
            }
          } else if (it.key() == "states") {
            REQUIRE(m.at("blocks").size() == it->size());
            for (size_t b = 0; b < it->size(); ++b) CHECK(m["blocks"][b]["state"] == (*it)[b]);
          } else if (it.key() == "overhang") {
            CHECK(m.at("overhang").get<double>() == it->get<double>());
          } else {
            CHECK(m.at(it.key()) == *it);
          }
        }
        CHECK_FALSE(m.contains("data"));
      } else {
        CHECK(have.at("schema") == "bricklayer.undecoded");
        CHECK(m.at("data_hex").get<std::string>().size() == 2 * want.at("undecoded_bytes").get<size_t>());
      }
    }
    total += msgs.size();
  }
  CHECK(read.size() == expected.size());
  CHECK(summary.at("messages").get<uint64_t>() == total);
  CHECK(total > 500);

  // The checker refuses a file cut short (its summary and footer are gone).
  fs::copy_file(mcap, dir / "cut.mcap");
  fs::resize_file(dir / "cut.mcap", fs::file_size(mcap) / 2);
  CHECK(run({kNode, kJs + "mcap_check.mjs", (dir / "cut.mcap").string()}, dir).code != 0);
}

TEST_CASE("the report page loads in Chromium with no console errors and its plots show data") {
  REQUIRE(fs::exists(kDemoLog));
  fs::path dir = output("page");
  Run r = run({kBin + "bricklayer-report", kDemoLog.string(), "--out", (dir / "report").string()}, dir);
  REQUIRE(r.code == 0);
  fs::path shot = dir / "report.png";
  Run page = run({kNode, kJs + "page_check.mjs", (dir / "report/index.html").string(), "--screenshot", shot.string()}, dir);
  INFO(page.err);
  REQUIRE(page.code == 0);
  json result = json::parse(page.out);
  INFO(page.out);
  CHECK(result.at("console").empty());
  CHECK(result.at("errors").empty());
  CHECK(result.at("failed_requests").empty());
  std::map<std::string, json> images;
  for (const auto& i : result.at("images")) images[i.at("id").get<std::string>()] = i;
  for (const char* id : {"plot-rounds", "plot-scores", "plot-red", "plot-red_durations", "plot-latency", "plot-rates", "plot-health", "plot-disk"}) {
    INFO(id);
    REQUIRE(images.count(id));
    CHECK(images[id].at("width").get<int>() == 900);
    CHECK(images[id].at("coloured").get<int>() > 1000);  // data drawn in colour, not only axes and text
    CHECK(fs::exists(dir / "report/plots" / (std::string(id).substr(5) + ".png")));
  }
  CHECK(fs::file_size(shot) > 10000);
  // Every table has rows; the page refers to nothing outside itself.
  std::set<std::string> tables;
  for (const auto& t : result.at("tables")) {
    CHECK(t.at("rows").get<int>() > 0);
    tables.insert(t.at("id").get<std::string>());
  }
  CHECK(tables.count("table-study"));
  CHECK(tables.count("table-study-tests"));
  std::string html = slurp(dir / "report/index.html");
  CHECK(html.find("src=\"data:image/png;base64,") != std::string::npos);
  CHECK(html.find("src=\"http") == std::string::npos);
  CHECK(html.find("<script") == std::string::npos);

  // The check sees a broken page: an error in a script, a plot with no data, an image that does not load.
  std::ofstream(dir / "broken.html")
      << "<!doctype html><html><head><title>broken</title></head><body>"
         "<img id=\"plot-blank\" src=\"data:image/png;base64,iVBORw0KGgoAAAANSUhEUgAAAAEAAAABCAAAAAA6fptVAAAACklEQVR4nGP4DwABAQEAG0qXkQAAAABJRU5ErkJggg==\">"
         "<img id=\"plot-missing\" src=\"missing.png\"><script>console.error('boom'); undefined_function();</script></body></html>";
  Run broken = run({kNode, kJs + "page_check.mjs", (dir / "broken.html").string()}, dir);
  REQUIRE(broken.code == 0);
  json b = json::parse(broken.out);
  CHECK_FALSE(b.at("errors").empty());
  CHECK_FALSE(b.at("console").empty());
  CHECK_FALSE(b.at("failed_requests").empty());
  for (const auto& i : b.at("images")) CHECK(i.at("coloured").get<int>() == 0);
}

TEST_CASE("a torn or corrupt log gives a clear error after everything readable was written") {
  REQUIRE(fs::exists(kDemoLog));
  const auto events = lcm_events(kDemoLog);
  fs::path dir = output("damaged");

  // Torn: the last 1000 bytes of the file are gone (the last event is cut). The demo log is recorded
  // afresh for every build, so the cut may fall exactly where an event starts, which would leave a
  // whole log: then one byte more stays, a torn event of one byte.
  fs::path torn = dir / "torn.lcmlog";
  fs::copy_file(kDemoLog, torn);
  uintmax_t cut = fs::file_size(kDemoLog) - 1000;
  if (slurp(kDemoLog).compare(cut, 4, "\xED\xA1\xDA\x01") == 0) ++cut;
  fs::resize_file(torn, cut);
  const size_t kept = lcm_events(torn).size();
  REQUIRE(kept < events.size());
  Run r = run({kBin + "bricklayer-export", torn.string(), "--csv", (dir / "torn-csv").string(), "--mcap", (dir / "torn.mcap").string()}, dir);
  CHECK(r.code == 1);
  CHECK_THAT(r.err, Catch::Contains("truncated") && Catch::Contains("damaged") && Catch::Contains("everything readable was written"));
  uint64_t messages = 0;
  for (const auto& line : lines(slurp(dir / "torn-csv/index.csv")))
    if (line.rfind("file,", 0) != 0) messages += std::stoull(line.substr(line.rfind(',', line.rfind(',') - 1) + 1));
  CHECK(messages == kept);
  Run mcap = run({kNode, kJs + "mcap_check.mjs", (dir / "torn.mcap").string()}, dir);
  INFO(mcap.err);
  CHECK(mcap.code == 0);  // a whole, indexed MCAP of what was read
  Run report = run({kBin + "bricklayer-report", torn.string(), "--out", (dir / "torn-report").string()}, dir);
  CHECK(report.code == 1);
  CHECK(fs::exists(dir / "torn-report/index.html"));
  CHECK_THAT(slurp(dir / "torn-report/index.html"), Catch::Contains("The log is damaged"));

  // Corrupt: 64 bytes overwritten from the first event header past the middle of the file (bytes
  // inside a JPEG would go unnoticed: they are opaque). The events around them are read.
  fs::path corrupt = dir / "corrupt.lcmlog";
  fs::copy_file(kDemoLog, corrupt);
  {
    std::string bytes = slurp(corrupt);
    size_t at = bytes.find("\xED\xA1\xDA\x01", bytes.size() / 2);
    REQUIRE(at != std::string::npos);
    std::fstream f(corrupt, std::ios::in | std::ios::out | std::ios::binary);
    f.seekp(static_cast<std::streamoff>(at));
    f.write(std::string(64, '\x5a').data(), 64);
  }
  Run c = run({kBin + "bricklayer-export", corrupt.string(), "--jsonl", (dir / "corrupt-jsonl").string()}, dir);
  CHECK(c.code == 1);
  CHECK_THAT(c.err, Catch::Contains("corrupt"));
  CHECK(lines(slurp(dir / "corrupt-jsonl/BL_HEARTBEAT.jsonl")).size() >= 5);

  // Not a log at all, and a missing file.
  std::ofstream(dir / "text.lcmlog") << "hello";
  Run t = run({kBin + "bricklayer-report", (dir / "text.lcmlog").string(), "--out", (dir / "text-report").string()}, dir);
  CHECK(t.code == 1);
  CHECK_THAT(t.err, Catch::Contains("no event could be read"));
  Run m = run({kBin + "bricklayer-export", (dir / "absent.lcmlog").string(), "--csv", (dir / "x").string()}, dir);
  CHECK(m.code == 1);
  CHECK_THAT(m.err, Catch::Contains("cannot read log"));
  Run u = run({kBin + "bricklayer-export", kDemoLog.string()}, dir);
  CHECK(u.code == 2);
  CHECK_THAT(u.err, Catch::Contains("nothing to do"));
}

TEST_CASE("long inputs show progress") {
  REQUIRE(fs::exists(kDemoLog));
  fs::path dir = output("progress");
  Run r = run({kBin + "bricklayer-export", kDemoLog.string(), kDemoLog.string(), "--csv", (dir / "csv").string(),
               "--progress-seconds", "0"},
              dir);
  REQUIRE(r.code == 0);
  CHECK_THAT(r.err, Catch::Contains("MB (") && Catch::Contains("MB/s"));
  Run quiet = run({kBin + "bricklayer-export", kDemoLog.string(), "--csv", (dir / "csv2").string(), "--progress-seconds", "0", "--quiet"}, dir);
  CHECK(quiet.err.find("MB/s") == std::string::npos);
}
