// bricklayer-study as a real process: report on real log files (text, CSV, exit codes), minimum on the
// shipped problems, check on a pile file, bad arguments.
#include <sys/wait.h>
#include <unistd.h>

#include <cstdio>
#include <fstream>
#include <sstream>
#include <string>

#include <catch2/catch.hpp>
#include <nlohmann/json.hpp>

#include "study_messages.h"

namespace {

struct Run {
  int status = -1;
  std::string out;
  std::string err;
};

std::string base_path(const std::string& name) {
  return std::string(BRICKLAYER_BINARY_DIR) + "/tests/study/cli_" + name + "_" + std::to_string(getpid());
}

std::string slurp(const std::string& path) {
  std::stringstream s;
  s << std::ifstream(path).rdbuf();
  return s.str();
}

Run study(const std::string& args) {
  static int counter = 0;
  const std::string base = base_path("run" + std::to_string(counter++));
  const std::string command = std::string(BRICKLAYER_BINARY_DIR) + "/bin/bricklayer-study " + args + " > " + base +
                              ".out 2> " + base + ".err < /dev/null";
  const int raw = std::system(command.c_str());
  Run r;
  r.status = WIFEXITED(raw) ? WEXITSTATUS(raw) : -1;
  r.out = slurp(base + ".out");
  r.err = slurp(base + ".err");
  std::remove((base + ".out").c_str());
  std::remove((base + ".err").c_str());
  return r;
}

std::string problem(const std::string& name) {
  return std::string(BRICKLAYER_SOURCE_DIR) + "/launch/problems/" + name + ".json";
}

}  // namespace

TEST_CASE("bricklayer-study report: text, both CSVs, and exit 1 for a study message that does not decode", "[cli]") {
  const std::string log = base_path("study") + ".lcmlog";
  {
    study_test::LogWriter w(log);
    for (const auto& s : study_test::scripted_subjects()) w.session(s);
  }
  const std::string csv = base_path("table") + ".csv";
  const std::string tests = base_path("tests") + ".csv";
  const Run r = study("report --csv " + csv + " --tests-csv " + tests + " " + log);
  CHECK(r.status == 0);
  CHECK(r.out.find("Table 1: per condition") != std::string::npos);
  CHECK(r.out.find("red vs proposed") != std::string::npos);
  CHECK(r.err.find("120 events, 120 study messages, 0 that did not decode") != std::string::npos);
  const std::string table = slurp(csv);
  CHECK(table.find("\nblue,3,100,2,1,3,1,1,0,113.3333333,3,1.116666667,0.01583333333\n") != std::string::npos);
  CHECK(table.find("\nred,3,100,2,1,3,1,2,0,113.6666667,3,1.133333333,0.02333333333\n") != std::string::npos);
  CHECK(table.find("\nproposed,4,87.5,3,1,3,0,2,0,137.5,3,1.6,0.13\n") != std::string::npos);
  const std::string pairs = slurp(tests);
  CHECK(pairs.rfind("a,b,n_a,n_b,f,f_df1,f_df2,f_p,t_kind,t,t_df,t_p,welch_t,welch_df,welch_p\n", 0) == 0);
  CHECK(pairs.find("\nblue,red,3,3,") != std::string::npos);

  // CSV to stdout replaces the text table.
  const Run to_stdout = study("report --csv - " + log);
  CHECK(to_stdout.status == 0);
  CHECK(to_stdout.out.rfind("condition,subjects,", 0) == 0);

  {
    study_test::LogWriter w(log);
    w.session(study_test::scripted_subjects()[0]);
    w.raw(bricklayer::study::kAnswerChannel, {0x01});
  }
  const Run bad = study("report " + log);
  CHECK(bad.status == 1);
  CHECK(bad.err.find("on BL_STUDY_ANSWER does not decode (1 bytes)") != std::string::npos);
  CHECK(bad.out.find("blue") != std::string::npos);  // the rest is still reported

  for (const std::string& f : {log, csv, tests}) std::remove(f.c_str());
}

TEST_CASE("bricklayer-study minimum and check on the shipped problems", "[cli]") {
  const Run m = study("minimum " + problem("stabilise-two") + " " + problem("stabilise-one") + " " + problem("score-100-four"));
  CHECK(m.status == 0);
  CHECK(m.out.find("stabilise-two: minimum 2 (proven: 0 and 1 impossible") != std::string::npos);
  CHECK(m.out.find("stabilise-one: minimum 1 (proven") != std::string::npos);
  CHECK(m.out.find("ERROR") == std::string::npos);

  const std::string pile = base_path("pile") + ".json";
  std::ofstream(pile) << R"({"blocks": [{"row": 0, "x": -2.4}, {"row": 0, "x": -1.2}, {"row": 1, "x": -0.6},
                                         {"row": 2, "x": -0.9}, {"row": 0, "x": -4.0}]})";
  const Run c = study("check " + problem("stabilise-one") + " " + pile);
  CHECK(c.status == 0);
  const auto j = nlohmann::json::parse(c.out);
  CHECK(j["outcome"] == "excess");
  CHECK(j["blocks_added"] == 2);
  CHECK(j["minimum_added"] == 1);
  CHECK(j["stands"] == true);
  std::remove(pile.c_str());

  // A problem file that declares a wrong minimum: exit 1 with the reason.
  const std::string wrong = base_path("wrong") + ".json";
  std::ofstream(wrong) << R"({"kind": "stabilise", "instruction": "x", "minimum_added": 2, "max_added": 2,
    "pile": {"blocks": [{"row": 0, "x": -0.3}]}, "solution": [{"row": 1, "x": -0.7}, {"row": 2, "x": -0.7}]})";
  const Run w = study("minimum " + wrong);
  CHECK(w.status == 1);
  CHECK(w.out.find("ERROR: the file declares minimum_added 2") != std::string::npos);
  std::remove(wrong.c_str());
}

TEST_CASE("bricklayer-study: bad arguments exit 2 with a message, --help exits 0", "[cli]") {
  CHECK(study("").status == 2);
  const Run unknown = study("frobnicate");
  CHECK(unknown.status == 2);
  CHECK(unknown.err.find("unknown command 'frobnicate'") != std::string::npos);
  CHECK(study("report").status == 2);
  CHECK(study("report --csv").status == 2);
  CHECK(study("report --colour x.lcmlog").status == 2);
  CHECK(study("check only-one").status == 2);
  const Run help = study("--help");
  CHECK(help.status == 0);
  CHECK(help.out.find("bricklayer-study report") != std::string::npos);
  const Run missing = study("report /nonexistent/study.lcmlog");
  CHECK(missing.status == 1);
  CHECK(missing.err.find("cannot be opened as an LCM log") != std::string::npos);
}

TEST_CASE("bricklayer-study script writes a scenario, and the session program checks its flags", "[cli]") {
  const std::string out = base_path("scenario") + ".json";
  const Run ok = study("script --trial1 50 --trial2 80 --answers correct,excess,failed --problems " +
                       std::string(BRICKLAYER_SOURCE_DIR) + "/launch/problems " + out);
  CHECK(ok.status == 0);
  const auto j = nlohmann::json::parse(slurp(out));
  CHECK(j["keyframes"].size() > 10);
  CHECK(j["description"].get<std::string>().find("problems 1-3 correct, excess, failed") != std::string::npos);
  std::remove(out.c_str());
  const std::string dir = " --problems " + std::string(BRICKLAYER_SOURCE_DIR) + "/launch/problems ";
  CHECK(study("script --answers correct,correct,excess" + dir + out).status == 2);  // problem 3 has no excess
  CHECK(study("script --trial1 500" + dir + out).status == 2);
  CHECK(study("script --problems /nonexistent " + out).status == 1);  // unreadable problem files: bad input
  CHECK(study("script --answers correct " + out).status == 2);
  CHECK(study("send sideways").status == 2);

  const std::string session = std::string(BRICKLAYER_BINARY_DIR) + "/bin/bricklayer-study-session";
  const std::string problems = std::string(BRICKLAYER_SOURCE_DIR) + "/launch/problems/";
  const std::string files = " --problem-1 " + problems + "stabilise-two.json --problem-2 " + problems +
                            "stabilise-one.json --problem-3 " + problems + "score-100-four.json";
  auto run = [](const std::string& command) {
    const int raw = std::system((command + " > /dev/null 2>&1").c_str());
    return WIFEXITED(raw) ? WEXITSTATUS(raw) : -1;
  };
  CHECK(run(session + " --help") == 0);
  CHECK(run(session + " --check-config --subject p01 --condition red" + files) == 0);
  CHECK(run(session + " --check-config --subject p01 --condition green" + files) == 2);
  CHECK(run(session + " --check-config --condition red" + files) == 2);  // no subject
}
