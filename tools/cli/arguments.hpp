// Command-line parsing shared by the jpcr programs: --name VALUE options, --flags, positionals,
// generated --help, and one exit-code convention (run_program).
#pragma once

#include <functional>
#include <map>
#include <stdexcept>
#include <string>
#include <vector>

namespace jpcr::cli {

/// A mistake in the command line; run_program prints it with a hint and exits 2.
class UsageError : public std::runtime_error {
 public:
  explicit UsageError(const std::string& what) : std::runtime_error(what) {}
};

class Arguments {
 public:
  Arguments(std::string program, std::string summary);

  /// --name VALUE. An empty default with required=false means "optional, no default".
  Arguments& option(const std::string& name, const std::string& help,
                    const std::string& default_value = "", bool required = false);
  Arguments& required(const std::string& name, const std::string& help) {
    return option(name, help, "", true);
  }
  /// --name without a value.
  Arguments& flag(const std::string& name, const std::string& help);
  /// A free-standing argument, in order.
  Arguments& positional(const std::string& name, const std::string& help);
  /// Extra text printed at the end of --help (examples).
  Arguments& epilog(const std::string& text);

  /// Parses argv[first..]. Returns false when --help was given (help already printed).
  bool parse(int argc, char** argv, int first = 1);

  bool has(const std::string& name) const;
  std::string get(const std::string& name) const;
  double get_double(const std::string& name) const;
  int get_int(const std::string& name) const;
  bool get_flag(const std::string& name) const;

  std::string help() const;
  const std::string& program() const { return program_; }

 private:
  struct Spec {
    std::string help;
    std::string default_value;
    bool required = false;
    bool is_flag = false;
  };

  std::string program_, summary_, epilog_;
  std::vector<std::string> order_;  // option names in declaration order
  std::map<std::string, Spec> specs_;
  std::vector<std::pair<std::string, std::string>> positionals_;  // name, help
  std::map<std::string, std::string> values_;
};

/// "WIDTHxHEIGHT" (each 1-16384) of option --`option`; a UsageError quoting the text otherwise.
void parse_image_size(const std::string& option, const std::string& text, int& width, int& height);

/// Runs body() and maps failures to exit codes: UsageError → 2 with a --help hint;
/// jpcr::InputError and other exceptions → 1 with "error: ..." on stderr; Interrupted
/// (stop_signal.hpp) → 128 + the signal (130 SIGINT, 143 SIGTERM) with "interrupted: ...".
int run_program(const std::string& program, const std::function<int()>& body);

}  // namespace jpcr::cli
