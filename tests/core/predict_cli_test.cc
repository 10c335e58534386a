// bricklayer-predict as a real process: exit codes, stdin, --jsonl with a bad line in the middle.
#include <sys/wait.h>

#include <algorithm>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <string>

#include <catch2/catch.hpp>
#include <nlohmann/json.hpp>

namespace {

struct Run {
  int status = -1;
  std::string out;
  std::string err;
};

// Runs bricklayer-predict with args, feeding `input` on stdin.
Run predict_cli(const std::string& args, const std::string& input) {
  static int counter = 0;
  const std::string base = std::string(BRICKLAYER_BINARY_DIR) + "/tests/core/cli_" + std::to_string(getpid()) + "_" +
                           std::to_string(counter++);
  {
    std::ofstream(base + ".in") << input;
  }
  const std::string command = std::string(BRICKLAYER_BINARY_DIR) + "/bin/bricklayer-predict " + args + " < " + base +
                              ".in > " + base + ".out 2> " + base + ".err";
  const int raw = std::system(command.c_str());
  Run r;
  r.status = WIFEXITED(raw) ? WEXITSTATUS(raw) : -1;
  std::stringstream out, err;
  out << std::ifstream(base + ".out").rdbuf();
  err << std::ifstream(base + ".err").rdbuf();
  r.out = out.str();
  r.err = err.str();
  for (const char* ext : {".in", ".out", ".err"}) std::remove((base + ext).c_str());
  return r;
}

const char* kUnbalanced = R"({"block_height": 0.333, "blocks": [{"id": 1, "row": 0, "x": -1.2}, {"id": 2, "row": 1, "x": -0.6}, {"id": 3, "row": 2, "x": -0.7}]})";
const char* kBalanced = R"({"blocks": [{"id": 5, "row": 0, "x": -0.5}]})";

}  // namespace

TEST_CASE("cli: one stack from stdin, exit 0 whatever the verdict") {
  const Run r = predict_cli("-", kUnbalanced);
  REQUIRE(r.status == 0);
  const auto j = nlohmann::json::parse(r.out);
  CHECK(j["balanced"] == false);
  CHECK(j["unbalanced"] == nlohmann::json::array({2}));
  CHECK(j["moving"] == nlohmann::json::array({2, 3}));
  CHECK(j["score"] == 40);
  CHECK(j["annotator"] == "exact");
  CHECK(j["solver"] == "nnls");  // the exact annotator's QP; no LP by default
  const Run b = predict_cli("--annotator paper --solver nlopt -", kBalanced);
  REQUIRE(b.status == 0);
  CHECK(nlohmann::json::parse(b.out)["balanced"] == true);
  CHECK(nlohmann::json::parse(b.out)["annotator"] == "paper");
}

TEST_CASE("cli: reads a file, the bundled example stacks all predict") {
  const Run r = predict_cli(std::string(BRICKLAYER_SOURCE_DIR) + "/launch/stacks/figure15-middle-alone.json", "");
  REQUIRE(r.status == 0);
  CHECK(nlohmann::json::parse(r.out)["unbalanced"] == nlohmann::json::array({1}));
  CHECK(nlohmann::json::parse(r.out)["name"] == "figure15-middle-alone");  // the input's label is echoed
  const Run all = predict_cli("--jsonl " + std::string(BRICKLAYER_SOURCE_DIR) + "/launch/stacks/examples.jsonl", "");
  CHECK(all.status == 0);
  CHECK(std::count(all.out.begin(), all.out.end(), '\n') >= 9);
  const Run missing = predict_cli("/nonexistent/stack.json", "");
  CHECK(missing.status == 1);
  CHECK(missing.err.find("cannot open") != std::string::npos);
}

TEST_CASE("cli: bad input is a one-line error and a non-zero exit") {
  const Run r = predict_cli("-", R"({"blocks": [{"id": 1, "row": 0, "x": 0}, {"id": 1, "row": 1, "x": 0}]})");
  CHECK(r.status == 1);
  CHECK(r.out.empty());
  CHECK(r.err.find("duplicate") != std::string::npos);
  CHECK(r.err.find('\n') == r.err.size() - 1);  // exactly one line
  const Run flags = predict_cli("--annotator magic -", kBalanced);
  CHECK(flags.status == 2);
  CHECK(flags.err.find("magic") != std::string::npos);
  CHECK(predict_cli("--solver cplex -", kBalanced).status == 2);
}

TEST_CASE("cli: --jsonl answers line by line, an error object for a bad line, and goes on") {
  const std::string input = std::string(kBalanced) + "\n{not json\n\n" + kUnbalanced + "\n" +
                            R"({"blocks": [{"row": 0, "x": 1e999}]})" + "\n";
  const Run r = predict_cli("--jsonl -", input);
  CHECK(r.status == 1);  // some line was bad
  std::istringstream lines(r.out);
  std::vector<nlohmann::json> out;
  for (std::string line; std::getline(lines, line);) out.push_back(nlohmann::json::parse(line));
  REQUIRE(out.size() == 4);  // the empty line is skipped
  CHECK(out[0]["balanced"] == true);
  CHECK(out[1].contains("error"));
  CHECK(out[1]["line"] == 2);
  CHECK(out[2]["unbalanced"] == nlohmann::json::array({2}));
  CHECK(out[3].contains("error"));
  const Run good = predict_cli("--jsonl -", std::string(kBalanced) + "\n" + kBalanced + "\n");
  CHECK(good.status == 0);
}

TEST_CASE("cli: --position-tolerance judges a measured knife edge as balanced, and says so") {
  const std::string past = R"({"blocks": [{"id": 1, "row": 0, "x": -0.497}]})";  // centre 0.003 past the edge
  Run exact = predict_cli("-", past);
  REQUIRE(exact.status == 0);
  CHECK_FALSE(nlohmann::json::parse(exact.out).at("balanced").get<bool>());
  CHECK_FALSE(nlohmann::json::parse(exact.out).contains("position_tolerance"));
  Run measured = predict_cli("--position-tolerance 0.005 -", past);
  REQUIRE(measured.status == 0);
  const auto j = nlohmann::json::parse(measured.out);
  CHECK(j.at("balanced").get<bool>());
  CHECK(j.at("position_tolerance").get<double>() == 0.005);
  Run bad = predict_cli("--position-tolerance -1 -", past);
  CHECK(bad.status == 2);
  CHECK(bad.err.find("--position-tolerance") != std::string::npos);
}
