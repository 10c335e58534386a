// One plot drawn by gnuplot (Debian's gnuplot-nox, pngcairo terminal): the data as tab-separated
// files beside the script, so every PNG of a report can be redrawn or restyled by hand.
#pragma once

#include <stdexcept>
#include <string>
#include <vector>

namespace bricklayer::inspect {

class PlotError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct Plot {
  std::string name;                 // file stem: NAME.png, NAME.gp, NAME*.tsv
  std::string script;               // gnuplot commands after the terminal and output lines
  std::vector<std::pair<std::string, std::string>> data;  // file name -> tab-separated text
  int width = 900, height = 300;    // pixels
};

// Writes the data and script into `dir` and runs `gnuplot_program` there; returns the PNG's path.
// Throws PlotError with gnuplot's own message when it fails.
std::string render_plot(const Plot& plot, const std::string& dir, const std::string& gnuplot_program = "gnuplot");

}  // namespace bricklayer::inspect
