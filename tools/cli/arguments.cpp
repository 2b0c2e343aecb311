#include "cli/arguments.hpp"

#include <cctype>
#include <cerrno>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <iostream>
#include <new>
#include <sstream>

#include "cli/stop_signal.hpp"
#include "jpcr/quadric/error.hpp"

namespace jpcr::cli {

Arguments::Arguments(std::string program, std::string summary)
    : program_(std::move(program)), summary_(std::move(summary)) {}

Arguments& Arguments::option(const std::string& name, const std::string& help,
                             const std::string& default_value, bool required) {
  order_.push_back(name);
  specs_[name] = Spec{help, default_value, required, false};
  return *this;
}

Arguments& Arguments::flag(const std::string& name, const std::string& help) {
  order_.push_back(name);
  specs_[name] = Spec{help, "", false, true};
  return *this;
}

Arguments& Arguments::positional(const std::string& name, const std::string& help) {
  positionals_.emplace_back(name, help);
  return *this;
}

Arguments& Arguments::epilog(const std::string& text) {
  epilog_ = text;
  return *this;
}

bool Arguments::parse(int argc, char** argv, int first) {
  std::size_t next_positional = 0;
  for (int i = first; i < argc; ++i) {
    std::string arg = argv[i];
    if (arg == "--help" || arg == "-h") {
      std::cout << help();
      return false;
    }
    if (arg.rfind("--", 0) == 0) {
      std::string name = arg.substr(2), value;
      const auto eq = name.find('=');
      const bool inline_value = eq != std::string::npos;
      if (inline_value) {
        value = name.substr(eq + 1);
        name = name.substr(0, eq);
      }
      const auto spec = specs_.find(name);
      if (spec == specs_.end()) throw UsageError("unknown option --" + name);
      if (spec->second.is_flag) {
        if (inline_value) throw UsageError("--" + name + " takes no value");
        values_[name] = "1";
        continue;
      }
      if (!inline_value) {
        if (i + 1 >= argc) throw UsageError("--" + name + " needs a value");
        value = argv[++i];
        // "--out --ply": the value was left out, and the next option would be taken for it.
        const std::string next =
            value.rfind("--", 0) == 0 ? value.substr(2, value.find('=') - 2) : std::string();
        if (!next.empty() && (specs_.count(next) || next == "help"))
          throw UsageError("--" + name + " needs a value (the next word, " + value +
                           ", is an option; write --" + name + "=" + value + " if it is meant)");
      }
      // An empty value is never meant: --out "" would write into the working directory.
      if (value.empty()) throw UsageError("--" + name + " needs a non-empty value");
      // Which of two values was meant is a guess, and a silent last-one-wins hides typos in
      // long command lines and scripts that append overrides.
      const auto earlier = values_.find(name);
      if (earlier != values_.end()) {
        throw UsageError("--" + name + " is given twice ('" + earlier->second + "', then '" +
                         value + "'); give it once");
      }
      values_[name] = value;
      continue;
    }
    if (next_positional >= positionals_.size())
      throw UsageError("unexpected argument '" + arg + "'");
    const std::string& name = positionals_[next_positional++].first;
    if (arg.empty()) throw UsageError(name + " needs a non-empty value");
    values_[name] = arg;
  }
  for (const auto& [name, spec] : specs_) {
    if (spec.required && !values_.count(name)) throw UsageError("--" + name + " is required");
  }
  if (next_positional < positionals_.size()) {
    throw UsageError("missing argument " + positionals_[next_positional].first);
  }
  return true;
}

bool Arguments::has(const std::string& name) const {
  if (values_.count(name)) return true;
  const auto spec = specs_.find(name);
  return spec != specs_.end() && !spec->second.is_flag && !spec->second.default_value.empty();
}

std::string Arguments::get(const std::string& name) const {
  const auto v = values_.find(name);
  if (v != values_.end()) return v->second;
  const auto spec = specs_.find(name);
  if (spec == specs_.end()) throw std::logic_error("Arguments::get: undeclared option " + name);
  return spec->second.default_value;
}

namespace {

// strtod and strtol skip leading white space and strtod reads hexadecimal ("0x10" is 16): a
// command line's number is a plain decimal token.
bool plain_token(const std::string& text) {
  return !text.empty() && !std::isspace(static_cast<unsigned char>(text[0])) &&
         text.find_first_of("xX") == std::string::npos;
}

}  // namespace

double Arguments::get_double(const std::string& name) const {
  const std::string text = get(name);
  char* end = nullptr;
  const double v = std::strtod(text.c_str(), &end);
  if (!plain_token(text) || end != text.c_str() + text.size()) {
    throw UsageError("--" + name + " expects a number, got '" + text + "'");
  }
  return v;
}

int Arguments::get_int(const std::string& name) const {
  const std::string text = get(name);
  char* end = nullptr;
  errno = 0;
  const long v = std::strtol(text.c_str(), &end, 10);
  if (!plain_token(text) || end != text.c_str() + text.size()) {
    throw UsageError("--" + name + " expects an integer, got '" + text + "'");
  }
  if (errno == ERANGE || v < -2147483647L || v > 2147483647L) {
    throw UsageError("--" + name + " is out of range (|n| <= 2147483647), got '" + text + "'");
  }
  return static_cast<int>(v);
}

bool Arguments::get_flag(const std::string& name) const {
  return values_.count(name) > 0;
}

std::string Arguments::help() const {
  std::ostringstream out;
  out << "usage: " << program_;
  for (const auto& [name, help] : positionals_)
    out << ' ' << name;
  for (const std::string& name : order_) {
    const Spec& s = specs_.at(name);
    const std::string text = s.is_flag ? "--" + name : "--" + name + " VALUE";
    out << ' ' << (s.required ? text : "[" + text + "]");
  }
  out << "\n\n" << summary_ << "\n\n";
  if (!positionals_.empty()) {
    out << "arguments:\n";
    for (const auto& [name, help] : positionals_)
      out << "  " << name << "\n      " << help << '\n';
  }
  out << "options:\n";
  for (const std::string& name : order_) {
    const Spec& s = specs_.at(name);
    out << "  --" << name << (s.is_flag ? "" : " VALUE") << "\n      " << s.help;
    if (s.required)
      out << " (required)";
    else if (!s.default_value.empty())
      out << " (default: " << s.default_value << ")";
    out << '\n';
  }
  out << "  --help\n      show this help and exit\n";
  if (!epilog_.empty()) out << '\n' << epilog_ << '\n';
  return out.str();
}

void parse_image_size(const std::string& option, const std::string& text, int& width, int& height) {
  // Digits only, at most 5 each: sscanf's %d would wrap 4294967376 to 80.
  const auto side = [&](std::size_t from, std::size_t to, int& out) {
    if (to <= from || to - from > 5) return false;
    out = 0;
    for (std::size_t i = from; i < to; ++i) {
      if (text[i] < '0' || text[i] > '9') return false;
      out = 10 * out + (text[i] - '0');
    }
    return out >= 1 && out <= 16384;
  };
  const std::size_t x = text.find('x');
  if (x == std::string::npos || !side(0, x, width) || !side(x + 1, text.size(), height)) {
    throw UsageError("--" + option + " expects WIDTHxHEIGHT, each 1-16384 (e.g. 640x480), got '" +
                     text + "'");
  }
}

int run_program(const std::string& program, const std::function<int()>& body) {
  // A reader that closes the pipe (jpcr_run ... | head -1) must not kill the run halfway, its
  // staging directory left behind: writes to the closed pipe fail quietly instead, and the
  // output files are written whole as ever.
  std::signal(SIGPIPE, SIG_IGN);
  try {
    return body();
  } catch (const UsageError& e) {
    std::cerr << program << ": " << e.what() << "\nTry '" << program << " --help'.\n";
    return 2;
  } catch (const Interrupted& e) {
    std::cerr << program << ": interrupted: " << e.what() << '\n';
    return e.exit_status();
  } catch (const InputError& e) {
    std::cerr << program << ": error: " << e.what() << '\n';
    return 1;
  } catch (const std::bad_alloc&) {
    std::cerr << program << ": error: out of memory: the image size, frame count or window asked "
              << "for needs more memory than this machine has\n";
    return 1;
  } catch (const std::exception& e) {
    std::cerr << program << ": error: " << e.what() << '\n';
    return 1;
  }
}

}  // namespace jpcr::cli
