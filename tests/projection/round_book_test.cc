// The round book on disk: what is saved reads back the same, a missing file is an empty book, a damaged
// or foreign file is a clear error naming the file, and a save replaces the file whole (no temporary
// left behind, an unwritable folder is an error, the old book still intact).
#include "bricklayer/projection/round_book.h"

#include <unistd.h>

#include <filesystem>
#include <fstream>

#include <catch2/catch.hpp>

using namespace bricklayer::projection;
namespace fs = std::filesystem;

namespace {
struct Folder {
  fs::path path = fs::temp_directory_path() / ("bricklayer-round-book-" + std::to_string(::getpid()));
  Folder() {
    fs::remove_all(path);
    fs::create_directories(path);
  }
  ~Folder() {
    std::error_code ec;
    fs::remove_all(path, ec);
  }
};
void write(const fs::path& p, const std::string& text) { std::ofstream(p, std::ios::binary) << text; }
}  // namespace

TEST_CASE("a round book reads back what was saved") {
  Folder dir;
  const std::string file = (dir.path / "rounds.json").string();
  CHECK(load_round_book(file) == RoundBook{});  // missing: empty
  RoundBook book;
  book.history.push_back({1'781'000'000'000'000, 1'781'000'180'000'000, 240, 4, 6, RoundEnd::kTimeUp});
  book.history.push_back({1'781'000'200'000'000, 1'781'000'230'000'000, 0, 0, 1, RoundEnd::kBoardCleared});
  book.history.push_back({1'781'000'300'000'000, 1'781'000'310'000'000, 90, 2, 2, RoundEnd::kReset});
  book.running = RoundRecord{1'781'000'400'000'000, 0, 130, 2, 3, RoundEnd::kTimeUp};
  save_round_book(file, book);
  CHECK(load_round_book(file) == book);
  CHECK_FALSE(fs::exists(file + ".tmp"));
  book.running.reset();
  save_round_book(file, book);  // replaces it
  CHECK(load_round_book(file) == book);
}

TEST_CASE("a damaged round book is an error that names the file") {
  Folder dir;
  const std::string file = (dir.path / "rounds.json").string();
  auto message = [&](const std::string& text) {
    write(file, text);
    try {
      load_round_book(file);
    } catch (const std::runtime_error& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  for (const std::string& text :
       {std::string("{\"version\": 1, \"rounds\": [{\"start_utime\": 5"),  // torn
        std::string("[1, 2, 3]"), std::string("{\"version\": 7, \"rounds\": []}"),
        std::string("{\"version\": 1, \"rounds\": [{\"start_utime\": 5}]}"),
        std::string("{\"version\": 1, \"rounds\": [{\"start_utime\": 5, \"end_utime\": 9, \"max_score\": 1, "
                    "\"blocks\": 1, \"most_blocks\": 1, \"end\": \"lunch\"}]}"),
        std::string("{\"version\": 1, \"rounds\": [{\"start_utime\": 5, \"end_utime\": 1, \"max_score\": 1, "
                    "\"blocks\": 1, \"most_blocks\": 1, \"end\": \"time up\"}]}"),
        std::string("{\"version\": 1, \"rounds\": [{\"start_utime\": \"x\", \"end_utime\": 9, \"max_score\": 1, "
                    "\"blocks\": 1, \"most_blocks\": 1, \"end\": \"time up\"}]}")}) {
    const std::string why = message(text);
    INFO(text << " -> " << why);
    CHECK(why.find("round book") != std::string::npos);
    CHECK(why.find(file) != std::string::npos);
  }
}

TEST_CASE("a save that cannot be written is an error and leaves the old book") {
  Folder dir;
  const std::string file = (dir.path / "rounds.json").string();
  RoundBook book;
  book.history.push_back({1, 2, 3, 1, 1, RoundEnd::kTimeUp});
  save_round_book(file, book);
  RoundBook bigger = book;
  bigger.history.push_back({3, 4, 5, 1, 1, RoundEnd::kTimeUp});
  // The temporary file cannot be created (a folder is in its place): works the same for root.
  fs::create_directories(file + ".tmp");
  CHECK_THROWS_AS(save_round_book(file, bigger), std::runtime_error);
  CHECK(load_round_book(file) == book);
  fs::remove_all(file + ".tmp");
  // A folder that does not exist.
  CHECK_THROWS_AS(save_round_book((dir.path / "no-such-folder" / "rounds.json").string(), book), std::runtime_error);
  // Nothing can be renamed over a folder: the temporary is removed again.
  const std::string over_folder = (dir.path / "a-folder").string();
  fs::create_directories(fs::path(over_folder) / "inside");
  CHECK_THROWS_AS(save_round_book(over_folder, book), std::runtime_error);
  CHECK_FALSE(fs::exists(over_folder + ".tmp"));
  save_round_book(file, bigger);
  CHECK(load_round_book(file) == bigger);
}
