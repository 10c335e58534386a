#include "bricklayer/inspect/report_page.h"

#include <openssl/evp.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <set>
#include <sstream>

#include "bricklayer/inspect/gnuplot.h"
#include "bricklayer/inspect/wall_clock.h"

namespace bricklayer::inspect {

namespace fs = std::filesystem;

namespace {

std::string base64(const std::string& bytes) {
  std::string out(4 * ((bytes.size() + 2) / 3) + 1, '\0');
  int n = EVP_EncodeBlock(reinterpret_cast<unsigned char*>(out.data()), reinterpret_cast<const unsigned char*>(bytes.data()),
                          static_cast<int>(bytes.size()));
  out.resize(static_cast<size_t>(n));
  return out;
}

std::string read_file(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

std::string fixed(double v, int digits) {
  std::ostringstream o;
  o << std::fixed << std::setprecision(digits) << v;
  return o.str();
}

std::string ms(const Json& us) { return us.is_number() ? fixed(us.get<double>() / 1000.0, 2) : "-"; }

// Text inside a single-quoted gnuplot string.
std::string gnuplot_quote(const std::string& s) {
  std::string out;
  for (char c : s) out += c == '\'' ? std::string("''") : std::string(1, c);
  return out;
}

// Seconds since the epoch as gnuplot reads them with timefmt "%s".
std::string tsec(int64_t us) { return fixed(static_cast<double>(us) / 1e6, 3); }

class Page {
 public:
  void h2(const std::string& id, const std::string& title) { html_ << "<section id=\"" << id << "\"><h2>" << html_escape(title) << "</h2>\n"; }
  void end_section() { html_ << "</section>\n"; }
  void p(const std::string& text, const std::string& cls = "") {
    html_ << "<p" << (cls.empty() ? "" : " class=\"" + cls + "\"") << ">" << html_escape(text) << "</p>\n";
  }
  void table(const std::vector<std::string>& header, const std::vector<std::vector<std::string>>& rows, const std::string& id) {
    html_ << "<table id=\"" << id << "\"><thead><tr>";
    for (const auto& h : header) html_ << "<th>" << html_escape(h) << "</th>";
    html_ << "</tr></thead><tbody>\n";
    for (const auto& r : rows) {
      html_ << "<tr>";
      for (const auto& c : r) html_ << "<td>" << html_escape(c) << "</td>";
      html_ << "</tr>\n";
    }
    html_ << "</tbody></table>\n";
  }
  void image(const std::string& id, const std::string& png_path, const std::string& alt) {
    html_ << "<img class=\"plot\" id=\"plot-" << id << "\" alt=\"" << html_escape(alt) << "\" src=\"data:image/png;base64,"
          << base64(read_file(png_path)) << "\">\n";
  }
  void raw(const std::string& s) { html_ << s; }
  std::string str() const { return html_.str(); }

 private:
  std::ostringstream html_;
};

class ReportWriter {
 public:
  ReportWriter(const ReportStats& s, const Json& n, std::string dir, const ReportOptions& o)
      : s_(s), n_(n), dir_(std::move(dir)), plots_((fs::path(dir_) / "plots").string()), o_(o) {
    const double span = n_.at("span_s").get<double>();
    time_format_ = span > 2 * 86400 ? "%m-%d %H:%M" : span > 600 ? "%H:%M" : span > 60 ? "%H:%M:%S" : "%H:%M:%.1S";
  }

  void write() {
    fs::create_directories(plots_);
    header();
    summary();
    rounds();
    red();
    latency();
    rates();
    health();
    disk();
    study();
    page_.raw("<footer>Made by bricklayer-report from " + html_escape(std::to_string(n_.at("events").get<uint64_t>())) +
              " log events; the numbers are in report.json, the plots' data and gnuplot scripts in plots/.</footer>\n</body></html>\n");
    std::ofstream out(fs::path(dir_) / "index.html", std::ios::trunc);
    out << page_.str();
    if (!out) throw std::runtime_error("cannot write " + (fs::path(dir_) / "index.html").string());
    std::ofstream numbers(fs::path(dir_) / "report.json", std::ios::trunc);
    numbers << n_.dump(2) << "\n";
    if (!numbers) throw std::runtime_error("cannot write " + (fs::path(dir_) / "report.json").string());
  }

 private:
  std::string time_axis() const {
    // Every plot over time spans the whole log, so they line up when read one below the other.
    return "set xdata time\nset timefmt '%s'\nset format x '" + time_format_ + "'\nset xlabel 'time (UTC)'\nset grid\n" +
           "set xrange ['" + tsec(s_.first_us()) + "':'" + tsec(std::max(s_.last_us(), s_.first_us() + 1000000)) + "']\n";
  }
  // Whole-number ticks for counts that stay small.
  static std::string count_axis(uint64_t largest) {
    return largest <= 10 ? "set ytics 1\nset yrange [0:" + std::to_string(std::max<uint64_t>(largest, 1)) + "]\n" : "set yrange [0:*]\n";
  }
  double bin_center(size_t i) const {
    return (static_cast<double>(s_.bin_origin_us()) + (static_cast<double>(i) + 0.5) * static_cast<double>(s_.bin_width_us())) / 1e6;
  }
  void plot(const std::string& id, Plot p, const std::string& alt) {
    p.name = id;
    page_.image(id, render_plot(p, plots_, o_.gnuplot), alt);
  }
  std::string bin_text() const { return fixed(static_cast<double>(s_.bin_width_us()) / 1e6, 0) + " s"; }

  void header() {
    const std::string title = "Bricklayer: " + n_.at("first_utc").get<std::string>().substr(0, 19) + " to " +
                              n_.at("last_utc").get<std::string>().substr(0, 19) + " UTC";
    page_.raw("<!doctype html>\n<html lang=\"en\"><head><meta charset=\"utf-8\"><title>" + html_escape(title) +
              "</title>\n<style>body{font-family:'DejaVu Sans',sans-serif;max-width:960px;margin:1em auto;color:#222}"
              "table{border-collapse:collapse;margin:.5em 0}td,th{border:1px solid #bbb;padding:2px 8px;text-align:right}"
              "th{background:#eef}td:first-child,th:first-child{text-align:left}img.plot{display:block;max-width:100%}"
              ".damage{background:#fdd;border:1px solid #c00;padding:.5em}.note{color:#555;font-size:90%}"
              "footer{color:#777;font-size:85%;margin-top:2em}</style></head><body>\n<h1>" +
              html_escape(title) + "</h1>\n");
    std::string logs;
    for (const auto& l : n_.at("logs")) logs += (logs.empty() ? "" : ", ") + l.get<std::string>();
    page_.p("Logs: " + logs + ". " + std::to_string(n_.at("events").get<uint64_t>()) + " events over " +
            fixed(n_.at("span_s").get<double>(), 1) + " s; time series in bins of " + bin_text() + ".");
    if (!n_.at("damage").empty() || n_.at("malformed").get<uint64_t>() > 0) {
      std::string what = "The log is damaged; the report covers what could be read.";
      for (const auto& d : n_.at("damage")) what += " " + d.at("file").get<std::string>() + ": " + d.at("what").get<std::string>() + ".";
      if (n_.at("malformed").get<uint64_t>() > 0) what += " " + std::to_string(n_.at("malformed").get<uint64_t>()) + " malformed message(s).";
      page_.p(what, "damage");
    }
  }

  void summary() {
    page_.h2("summary", "At a glance");
    const Json& r = n_.at("rounds_summary");
    const Json& red = n_.at("red_summary");
    const Json& lat = n_.at("latency_us");
    uint64_t restarts = 0, errors = 0;
    for (const auto& m : n_.at("modules")) {
      restarts += m.at("restarts_seen").get<uint64_t>();
      errors += m.at("errors").get<uint64_t>();
    }
    std::vector<std::vector<std::string>> rows = {
        {"rounds", std::to_string(r.at("count").get<uint64_t>())},
        {"best MAX (points)", r.contains("best_max_points") ? std::to_string(r.at("best_max_points").get<int64_t>()) : "-"},
        {"median MAX (points)", r.contains("median_max_points") ? std::to_string(r.at("median_max_points").get<int64_t>()) : "-"},
        {"red episodes", std::to_string(red.at("episodes").get<uint64_t>())},
        {"piles that fell", std::to_string(red.at("fell").get<uint64_t>()) + " (" + fixed(red.at("fell_per_hour").get<double>(), 1) + " per hour)"},
        {"red lasted, median (s)", red.at("duration_us").contains("p50") ? fixed(red.at("duration_us").at("p50").get<double>() / 1e6, 3) : "-"},
        {"end-to-end latency p50 / p99 (ms)", lat.contains("p50") ? ms(lat.at("p50")) + " / " + ms(lat.at("p99")) : "-"},
        {"module restarts", std::to_string(restarts)},
        {"module errors", std::to_string(errors)},
        {"log size (MB)", fixed(static_cast<double>(n_.at("disk").at("bytes").get<uint64_t>()) / 1e6, 2) + " (" +
                              fixed(n_.at("disk").at("mb_per_hour").get<double>(), 0) + " MB per hour)"}};
    page_.table({"what", "value"}, rows, "table-summary");
    page_.end_section();
  }

  void rounds() {
    page_.h2("rounds", "Rounds and their MAX");
    const Json& rounds = n_.at("rounds");
    if (rounds.empty()) {
      page_.p("No round ran in this log (a round starts with the S key or a START_ROUND command).", "note");
      page_.end_section();
      return;
    }
    std::ostringstream data;
    std::map<int64_t, uint64_t> histogram;
    for (const auto& r : rounds) {
      data << tsec(r.at("end_utime_us").get<int64_t>()) << "\t" << r.at("max_score_points").get<int64_t>() << "\n";
      histogram[static_cast<int64_t>(std::floor(r.at("max_score_points").get<double>() / 10.0)) * 10]++;
    }
    plot("rounds", Plot{"", time_axis() + "set ylabel 'MAX (points)'\nset key off\nset yrange [0:*]\n"
                            "plot 'rounds.tsv' using 1:2 with impulses lw 3 lc rgb '#1f5fbf', '' using 1:2 with points pt 7 ps 1.2 lc rgb '#1f5fbf'",
                        {{"rounds.tsv", data.str()}}},
         "MAX of every round over time");
    std::ostringstream h;
    uint64_t most = 0;
    for (const auto& [lo, count] : histogram) {
      h << lo + 5 << "\t" << count << "\n";
      most = std::max(most, count);
    }
    page_.p("Distribution of the rounds' MAX scores (10-point bins):", "note");
    plot("scores", Plot{"", "set xlabel 'MAX (points)'\nset ylabel 'rounds'\nset key off\nset grid\nset boxwidth 9\nset style fill solid 0.8\n" +
                            count_axis(most) + "plot 'scores.tsv' using 1:2 with boxes lc rgb '#1f5fbf'",
                        {{"scores.tsv", h.str()}}, 900, 260},
         "distribution of the rounds' MAX scores");
    std::vector<std::vector<std::string>> rows;
    for (const auto& r : rounds)
      rows.push_back({r.at("start_utc").get<std::string>().substr(0, 19), fixed(r.at("duration_s").get<double>(), 1),
                      std::to_string(r.at("max_score_points").get<int64_t>()), std::to_string(r.at("num_blocks").get<int64_t>()),
                      r.at("ended").get<std::string>()});
    if (rows.size() > 100) rows.erase(rows.begin(), rows.end() - 100);
    page_.table({"started (UTC)", "lasted (s)", "MAX (points)", "blocks at the end", "ended"}, rows, "table-rounds");
    page_.end_section();
  }

  void red() {
    page_.h2("red", "Piles that fell, and how long red lasted");
    const Json& episodes = n_.at("red_episodes");
    if (episodes.empty()) {
      page_.p("No pile turned red in this log.", "note");
      page_.end_section();
      return;
    }
    std::ostringstream data;
    uint64_t most = 0;
    for (size_t i = 0; i < s_.bins().size(); ++i) {
      data << fixed(bin_center(i), 3) << "\t" << s_.bins()[i].red_started << "\t" << s_.bins()[i].fell << "\n";
      most = std::max(most, s_.bins()[i].red_started);
    }
    plot("red", Plot{"", time_axis() + "set ylabel 'per " + bin_text() + "'\n" + count_axis(most) + "set style fill solid 0.7\n"
                         "set boxwidth " + fixed(static_cast<double>(s_.bin_width_us()) / 1e6 * 0.8, 3) + "\n"
                         "plot 'red.tsv' using 1:2 with boxes lc rgb '#d62728' title 'turned red', "
                         "'' using 1:3 with boxes lc rgb '#7f1f1f' title 'fell'",
                     {{"red.tsv", data.str()}}},
         "red episodes and falls over time");
    // Durations histogram, bins of a round number of seconds giving about 20 bins.
    double longest = 0;
    for (const auto& e : episodes)
      if (!e.at("open").get<bool>()) longest = std::max(longest, e.at("duration_us").get<double>() / 1e6);
    double width = 0.1;
    for (double w : {0.1, 0.2, 0.5, 1.0, 2.0, 5.0, 10.0, 30.0, 60.0})
      if (longest / w <= 20) {
        width = w;
        break;
      }
    std::map<int64_t, uint64_t> histogram;
    for (const auto& e : episodes)
      if (!e.at("open").get<bool>()) histogram[static_cast<int64_t>(std::floor(e.at("duration_us").get<double>() / 1e6 / width))]++;
    std::ostringstream h;
    uint64_t most_long = 0;
    for (const auto& [k, count] : histogram) {
      h << fixed((static_cast<double>(k) + 0.5) * width, 3) << "\t" << count << "\n";
      most_long = std::max(most_long, count);
    }
    if (!histogram.empty())
      plot("red_durations", Plot{"", "set xlabel 'red lasted (s)'\nset ylabel 'episodes'\nset key off\nset grid\n" + count_axis(most_long) + "set xrange [0:*]\n"
                                     "set style fill solid 0.8\nset boxwidth " + fixed(width * 0.9, 3) + "\n"
                                     "plot 'red_durations.tsv' using 1:2 with boxes lc rgb '#d62728'",
                                 {{"red_durations.tsv", h.str()}}, 900, 260},
           "how long red lasted");
    const Json& red = n_.at("red_summary");
    page_.p(std::to_string(red.at("episodes").get<uint64_t>()) + " red episodes: " + std::to_string(red.at("fell").get<uint64_t>()) +
                " fell (the pile after red had fewer blocks), " + std::to_string(red.at("fixed").get<uint64_t>()) + " were fixed, " +
                std::to_string(red.at("open").get<uint64_t>()) + " still red when the log ended.",
            "note");
    std::vector<std::vector<std::string>> rows;
    std::vector<Json> longest_first(episodes.begin(), episodes.end());
    std::stable_sort(longest_first.begin(), longest_first.end(), [](const Json& a, const Json& b) {
      return a.at("duration_us").get<int64_t>() > b.at("duration_us").get<int64_t>();
    });
    if (longest_first.size() > 20) longest_first.resize(20);
    for (const auto& e : longest_first)
      rows.push_back({e.at("start_utc").get<std::string>().substr(0, 23), fixed(e.at("duration_us").get<double>() / 1e6, 3),
                      std::to_string(e.at("blocks_red").get<int64_t>()), std::to_string(e.at("blocks_after").get<int64_t>()),
                      e.at("open").get<bool>() ? "still red" : e.at("fell").get<bool>() ? "fell" : "fixed"});
    page_.table({"turned red (UTC)", "lasted (s)", "blocks", "blocks after", "outcome"}, rows, "table-red");
    page_.end_section();
  }

  void latency() {
    page_.h2("latency", "End-to-end latency: camera frame to projector frame");
    const Json& lat = n_.at("latency_us");
    if (lat.at("samples").get<uint64_t>() == 0) {
      page_.p("No projection timings (timing_t, stage \"present\") in this log.", "note");
    } else {
      std::ostringstream data;
      for (size_t i = 0; i < s_.bins().size(); ++i) {
        const ValueCounts& v = s_.bins()[i].latency_us;
        if (v.empty()) continue;
        data << fixed(bin_center(i), 3) << "\t" << v.percentile(50) / 1000.0 << "\t" << v.percentile(90) / 1000.0 << "\t"
             << v.percentile(99) / 1000.0 << "\t" << v.max() / 1000.0 << "\n";
      }
      plot("latency", Plot{"", time_axis() + "set ylabel 'ms'\nset yrange [0:*]\nset key top left\n"
                               "plot 'latency.tsv' using 1:2 with linespoints pt 7 ps 0.6 lw 2 lc rgb '#1f5fbf' title 'p50', "
                               "'' using 1:3 with linespoints pt 7 ps 0.6 lw 2 lc rgb '#2ca02c' title 'p90', "
                               "'' using 1:4 with linespoints pt 7 ps 0.6 lw 2 lc rgb '#ff7f0e' title 'p99', "
                               "'' using 1:5 with points pt 1 ps 0.8 lc rgb '#d62728' title 'max'",
                           {{"latency.tsv", data.str()}}},
           "end-to-end latency percentiles over time");
      page_.p("Per bin of " + bin_text() + ", from the projection's \"present\" timings: capture time of the camera frame to the projector frame presented; nearest-rank percentiles of values rounded down to 10 us. Whole log: p50 " +
                  ms(lat.at("p50")) + " ms, p90 " + ms(lat.at("p90")) + " ms, p99 " + ms(lat.at("p99")) + " ms, max " + ms(lat.at("max")) +
                  " ms over " + std::to_string(lat.at("samples").get<uint64_t>()) + " frames.",
              "note");
    }
    std::vector<std::vector<std::string>> rows;
    for (const auto& st : n_.at("stages_elapsed_us"))
      rows.push_back({st.at("module").get<std::string>() + " / " + st.at("stage").get<std::string>(),
                      std::to_string(st.at("samples").get<uint64_t>()), ms(st.at("p50")), ms(st.at("p99")), ms(st.at("max"))});
    if (!rows.empty()) page_.table({"module / stage", "samples", "p50 (ms)", "p99 (ms)", "max (ms)"}, rows, "table-stages");
    page_.end_section();
  }

  void rates() {
    page_.h2("rates", "Frame rates");
    // The channels of the pipeline: frames, stacks, predictions, projector states.
    static const std::set<std::string> kPipeline = {"bricklayer.image_t", "bricklayer.stack_t", "bricklayer.prediction_t",
                                                    "bricklayer.projector_state_t"};
    std::vector<std::string> channels;
    for (const auto& [name, c] : s_.channels())
      if (kPipeline.count(c.type)) channels.push_back(name);
    if (!channels.empty()) {
      std::ostringstream data;
      const double width_s = static_cast<double>(s_.bin_width_us()) / 1e6;
      for (size_t i = 0; i < s_.bins().size(); ++i) {
        data << fixed(bin_center(i), 3);
        for (const auto& c : channels) {
          auto it = s_.bins()[i].messages.find(c);
          data << "\t" << (it == s_.bins()[i].messages.end() ? 0.0 : static_cast<double>(it->second) / width_s);
        }
        data << "\n";
      }
      std::string script = time_axis() + "set ylabel 'messages per second'\nset yrange [0:*]\nset key outside right\nplot ";
      for (size_t k = 0; k < channels.size(); ++k)
        script += std::string(k ? ", " : "") + "'rates.tsv' using 1:" + std::to_string(k + 2) + " with lines lw 2 title '" + gnuplot_quote(channels[k]) + "'";
      plot("rates", Plot{"", script, {{"rates.tsv", data.str()}}}, "messages per second of the pipeline's channels");
    }
    std::vector<std::vector<std::string>> rows;
    for (const auto& c : n_.at("channels"))
      rows.push_back({c.at("channel").get<std::string>(), c.at("type").get<std::string>(), std::to_string(c.at("messages").get<uint64_t>()),
                      fixed(c.at("rate_hz").get<double>(), 2)});
    page_.table({"channel", "type", "messages", "per second"}, rows, "table-channels");
    page_.end_section();
  }

  void health() {
    page_.h2("health", "Module restarts and errors");
    uint64_t most = 0;
    std::ostringstream data;
    for (size_t i = 0; i < s_.bins().size(); ++i) {
      data << fixed(bin_center(i), 3) << "\t" << s_.bins()[i].errors << "\t" << s_.bins()[i].restarts << "\n";
      most = std::max({most, s_.bins()[i].errors, s_.bins()[i].restarts});
    }
    if (most > 0)
      plot("health", Plot{"", time_axis() + "set ylabel 'per " + bin_text() + "'\n" + count_axis(most) + "set style fill solid 0.7\n"
                              "set boxwidth " + fixed(static_cast<double>(s_.bin_width_us()) / 1e6 * 0.8, 3) + "\n"
                              "plot 'health.tsv' using 1:2 with boxes lc rgb '#ff7f0e' title 'errors', "
                              "'' using 1:3 with impulses lw 4 lc rgb '#9467bd' title 'restarts'",
                          {{"health.tsv", data.str()}}, 900, 260},
           "module errors and restarts over time");
    else
      page_.p("No module restarted and none counted an error.", "note");
    std::vector<std::vector<std::string>> rows;
    for (const auto& m : n_.at("modules"))
      rows.push_back({m.at("module").get<std::string>(), std::to_string(m.at("heartbeats").get<uint64_t>()),
                      std::to_string(m.at("restarts_seen").get<uint64_t>()), std::to_string(m.at("launcher_restarts").get<int64_t>()),
                      std::to_string(m.at("errors").get<uint64_t>()), std::to_string(m.at("dropped").get<uint64_t>()),
                      m.at("last_status").get<std::string>()});
    page_.table({"module", "heartbeats", "restarts (new instance)", "restarts (launcher's count)", "errors", "dropped (newest wins)", "last status"},
                rows, "table-modules");
    page_.end_section();
  }

  void disk() {
    page_.h2("disk", "Disk use");
    std::ostringstream data;
    uint64_t total = 0;
    for (size_t i = 0; i < s_.bins().size(); ++i) {
      total += s_.bins()[i].bytes;
      data << fixed(bin_center(i), 3) << "\t" << static_cast<double>(total) / 1e6 << "\n";
    }
    plot("disk", Plot{"", time_axis() + "set ylabel 'log size (MB)'\nset yrange [0:*]\nset key off\n"
                          "plot 'disk.tsv' using 1:2 with lines lw 2 lc rgb '#1f5fbf'",
                      {{"disk.tsv", data.str()}}, 900, 260},
         "log size over time");
    std::vector<std::vector<std::string>> rows;
    const double span = n_.at("span_s").get<double>();
    for (const auto& c : n_.at("channels"))
      rows.push_back({c.at("channel").get<std::string>(), fixed(c.at("bytes").get<double>() / 1e6, 3),
                      fixed(100.0 * c.at("share").get<double>(), 1),
                      span > 0 ? fixed(c.at("bytes").get<double>() / 1e6 * 3600.0 / span, 0) : "-"});
    page_.table({"channel", "MB", "share (%)", "MB per hour"}, rows, "table-disk");
    page_.end_section();
  }

  void study() {
    if (!n_.contains("study")) return;  // no study session in this log
    const Json& st = n_.at("study");
    page_.h2("study", "Study sessions (the seed paper's Table 1)");
    page_.p(std::to_string(st.at("sessions").get<uint64_t>()) + " session(s) in the log. Per display condition: subjects, the first and second trial's average score, how many solved each problem (correct or with excess blocks) and how many of them used excess blocks, and the ratio trial 2 / trial 1 (the study module's Table 1: modules/study/README.md).",
            "note");
    auto num = [](const Json& v, int digits) { return v.is_number() ? fixed(v.get<double>(), digits) : std::string("-"); };
    std::vector<std::vector<std::string>> rows;
    for (const auto& r : st.at("rows")) {
      std::vector<std::string> row = {r.at("condition").get<std::string>(), std::to_string(r.at("subjects").get<uint64_t>()),
                                      num(r.at("trial1_mean_points"), 1)};
      for (int k = 0; k < 3; ++k)
        row.push_back(std::to_string(r.at("solved")[k].get<uint64_t>()) + " (" + std::to_string(r.at("excess")[k].get<uint64_t>()) + ")");
      row.push_back(num(r.at("trial2_mean_points"), 1));
      row.push_back(num(r.at("ratio_mean"), 3));
      row.push_back(num(r.at("ratio_variance"), 3));
      rows.push_back(row);
    }
    page_.table({"condition", "subjects", "trial 1 mean", "problem 1 solved (excess)", "problem 2 solved (excess)",
                 "problem 3 solved (excess)", "trial 2 mean", "ratio mean", "ratio variance"},
                rows, "table-study");
    std::vector<std::vector<std::string>> pairs;
    for (const auto& p : st.at("pairs"))
      pairs.push_back({p.at("a").get<std::string>() + " vs " + p.at("b").get<std::string>(), num(p.at("f"), 3), num(p.at("f_p"), 4),
                       p.at("t_pooled").get<bool>() ? "pooled" : "Welch", num(p.at("t"), 3), num(p.at("t_df"), 1), num(p.at("t_p"), 4),
                       num(p.at("welch_p"), 4)});
    if (!pairs.empty())
      page_.table({"conditions", "F", "p (F)", "t-test", "t", "df", "p (t)", "p (Welch)"}, pairs, "table-study-tests");
    std::string left_out;
    for (const auto& e : st.at("excluded")) left_out += (left_out.empty() ? "" : "; ") + e.get<std::string>();
    for (const auto& e : st.at("problems")) left_out += (left_out.empty() ? "" : "; ") + e.get<std::string>();
    if (!left_out.empty()) page_.p("Left out: " + left_out + ".", "note");
    page_.end_section();
  }

  const ReportStats& s_;
  const Json& n_;
  std::string dir_;
  std::string plots_;
  const ReportOptions& o_;
  std::string time_format_;
  Page page_;
};

}  // namespace

std::string html_escape(const std::string& text) {
  std::string out;
  for (char c : text) {
    switch (c) {
      case '&': out += "&amp;"; break;
      case '<': out += "&lt;"; break;
      case '>': out += "&gt;"; break;
      case '"': out += "&quot;"; break;
      case '\'': out += "&#39;"; break;
      default: out += c;
    }
  }
  return out;
}

void write_report(const ReportStats& stats, const Json& numbers, const std::string& dir, const ReportOptions& options) {
  ReportWriter(stats, numbers, dir, options).write();
}

}  // namespace bricklayer::inspect
