// A small command-line parser: --name=value or --name value, boolean --name, positional arguments,
// and --help text generated from the declarations. Unknown flags and bad values are errors that say
// how to fix them (the caller prints them and exits 2).
#pragma once

#include <map>
#include <stdexcept>
#include <string>
#include <vector>

namespace bricklayer {

class FlagError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

class Flags {
 public:
  Flags(std::string program, std::string summary);

  // Declarations: the default is what get() returns when the flag is absent.
  void add(const std::string& name, const std::string& default_value, const std::string& help);
  void add_bool(const std::string& name, const std::string& help);
  void add_positional(const std::string& name, const std::string& help, bool required = true);
  // The last positional argument: one or more values ("LOG..."), all in positional().
  void add_positional_list(const std::string& name, const std::string& help);

  // Parses argv; returns false when --help was given (help already printed to stdout).
  // Throws FlagError on unknown flags, missing values or missing positional arguments.
  bool parse(int argc, const char* const* argv);

  std::string get(const std::string& name) const;
  bool get_bool(const std::string& name) const;
  int64_t get_int(const std::string& name) const;    // throws FlagError naming the flag when not an integer
  double get_double(const std::string& name) const;  // throws FlagError when not a finite number
  bool was_set(const std::string& name) const;
  const std::vector<std::string>& positional() const { return positional_; }
  std::string help() const;

 private:
  struct Spec {
    std::string default_value;
    std::string help;
    bool is_bool = false;
  };
  std::string program_;
  std::string summary_;
  std::map<std::string, Spec> specs_;
  std::vector<std::string> order_;
  std::vector<std::pair<std::string, std::string>> positional_specs_;
  size_t required_positionals_ = 0;
  bool positional_list_ = false;
  std::map<std::string, std::string> values_;
  std::vector<std::string> positional_;
};

// Runs body() and turns FlagError / std::exception into "program: error: ..." and exit code 2 / 1.
// Keeps every main() to one line.
int run_main(const char* program, int (*body)(int, char**), int argc, char** argv);

}  // namespace bricklayer
