#include "jpcr/io/yaml_reader.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstring>
#include <limits>
#include <set>
#include <sstream>
#include <vector>

#include <yaml-cpp/depthguard.h>
#include <yaml-cpp/eventhandler.h>

#include "jpcr/io/atomic_file.hpp"
#include "jpcr/quadric/error.hpp"

namespace jpcr {

namespace {

std::string line_of(const YAML::Node& node) {
  const YAML::Mark mark = node.Mark();
  return mark.is_null() ? "" : std::to_string(mark.line + 1) + ":";
}

// Counts the documents of a stream that hold something (a closing '---' leaves an empty one),
// and proves that the parser gets through the stream: yaml-cpp 0.7 returns from
// HandleNextDocument without consuming a stray ',' at the top ("," alone), so YAML::LoadAll
// looped forever on such text, keeping a node per turn. A document starts only at a line's
// start, so more turns than lines are the parser standing still: a syntax error at the mark
// where it stands. (Lines are counted in bytes, '\n' or '\r', which holds for UTF-16 too.)
class DocumentCounter : public YAML::EventHandler {
 public:
  int given = 0;
  YAML::Mark last;
  void OnDocumentStart(const YAML::Mark& mark) override {
    root_ = true;
    last = mark;
  }
  void OnDocumentEnd() override {}
  void OnNull(const YAML::Mark&, YAML::anchor_t) override { root_ = false; }
  void OnAlias(const YAML::Mark&, YAML::anchor_t) override { content(); }
  void OnScalar(const YAML::Mark&, const std::string&, YAML::anchor_t,
                const std::string&) override {
    content();
  }
  void OnSequenceStart(const YAML::Mark&, const std::string&, YAML::anchor_t,
                       YAML::EmitterStyle::value) override {
    content();
  }
  void OnSequenceEnd() override {}
  void OnMapStart(const YAML::Mark&, const std::string&, YAML::anchor_t,
                  YAML::EmitterStyle::value) override {
    content();
  }
  void OnMapEnd() override {}

 private:
  void content() {
    if (root_) ++given;
    root_ = false;
  }
  bool root_ = false;
};

int count_documents(const std::string& text) {
  const std::size_t lines =
      1 + static_cast<std::size_t>(std::count_if(text.begin(), text.end(),
                                                 [](char c) { return c == '\n' || c == '\r'; }));
  std::istringstream stream(text);
  YAML::Parser parser(stream);
  DocumentCounter counter;
  for (std::size_t turn = 0; parser.HandleNextDocument(counter); ++turn) {
    if (turn > lines)
      throw YAML::ParserException(counter.last, "cannot read past column " +
                                                    std::to_string(counter.last.column + 1) +
                                                    " (a stray ',' or ']'?)");
  }
  return counter.given;
}

}  // namespace

YamlSection::YamlSection(const YAML::Node& node, std::string file, std::string path)
    : node_(node), file_(std::move(file)), path_(std::move(path)) {
  if (node_ && !node_.IsNull() && !node_.IsMap()) {
    throw InputError(file_ + ":" + line_of(node_) + " '" + (path_.empty() ? "<top>" : path_) +
                     "' must be a map of key: value");
  }
}

std::string YamlSection::qualified(const std::string& key) const {
  return path_.empty() ? key : path_ + "." + key;
}

void YamlSection::fail(const std::string& key, const std::string& problem) const {
  const YAML::Node& node = node_;
  const YAML::Node n = (node && node.IsMap()) ? node[key] : YAML::Node();
  const std::string where = n ? line_of(n) : "";
  throw InputError(file_ + ":" + where + " key '" + qualified(key) + "': " + problem);
}

bool YamlSection::has(const std::string& key) const {
  if (!node_ || !node_.IsMap()) return false;
  const YAML::Node& node = node_;
  const YAML::Node n = node[key];
  return n && !n.IsNull();
}

bool YamlSection::take(const std::string& key, YAML::Node& out) {
  if (!node_ || !node_.IsMap()) return false;
  const YAML::Node& node = node_;
  const YAML::Node n = node[key];
  if (!n) return false;
  used_.insert(key);  // a key given as null ("key:") is known and keeps the default
  if (n.IsNull()) return false;
  out = n;
  return true;
}

void YamlSection::read(const std::string& key, double& value) {
  YAML::Node n;
  if (!take(key, n)) return;
  if (!n.IsScalar()) fail(key, "expected a number");
  double v = 0.0;
  if (!YAML::convert<double>::decode(n, v) || !std::isfinite(v)) {
    fail(key, "expected a finite number, got '" + n.Scalar() + "'");
  }
  value = v;
}

void YamlSection::read(const std::string& key, float& value) {
  double v = value;
  read(key, v);
  if (std::abs(v) > std::numeric_limits<float>::max()) fail(key, "number out of range");
  value = static_cast<float>(v);
}

void YamlSection::read(const std::string& key, int& value) {
  YAML::Node n;
  if (!take(key, n)) return;
  long long v = 0;
  if (!n.IsScalar() || !YAML::convert<long long>::decode(n, v)) {
    fail(key, "expected an integer, got '" +
                  (n.IsScalar() ? n.Scalar() : std::string("a list or map")) + "'");
  }
  if (v < std::numeric_limits<int>::min() || v > std::numeric_limits<int>::max()) {
    fail(key, "integer out of range");
  }
  value = static_cast<int>(v);
}

void YamlSection::read(const std::string& key, bool& value) {
  YAML::Node n;
  if (!take(key, n)) return;
  bool v = false;
  if (!n.IsScalar() || !YAML::convert<bool>::decode(n, v)) {
    fail(key, "expected true or false, got '" +
                  (n.IsScalar() ? n.Scalar() : std::string("a list or map")) + "'");
  }
  value = v;
}

void YamlSection::read(const std::string& key, std::string& value) {
  YAML::Node n;
  if (!take(key, n)) return;
  if (!n.IsScalar()) fail(key, "expected a string");
  value = n.Scalar();
}

void YamlSection::read(const std::string& key, std::vector<double>& value) {
  YAML::Node n;
  if (!take(key, n)) return;
  if (!n.IsSequence()) fail(key, "expected a list of numbers");
  std::vector<double> out;
  for (const YAML::Node& item : n) {
    double v = 0.0;
    if (!item.IsScalar() || !YAML::convert<double>::decode(item, v) || !std::isfinite(v)) {
      fail(key, "expected a list of finite numbers");
    }
    out.push_back(v);
  }
  value = std::move(out);
}

void YamlSection::read_choice(const std::string& key, std::string& value,
                              const std::vector<std::string>& choices) {
  std::string v = value;
  read(key, v);
  for (const std::string& c : choices) {
    if (c == v) {
      value = v;
      return;
    }
  }
  std::string list;
  for (const std::string& c : choices)
    list += (list.empty() ? "" : " | ") + c;
  fail(key, "expected one of " + list + ", got '" + v + "'");
}

YamlSection YamlSection::section(const std::string& key) {
  YAML::Node n;
  if (!take(key, n)) return YamlSection(YAML::Node(), file_, qualified(key));
  return YamlSection(n, file_, qualified(key));
}

std::vector<YamlSection> YamlSection::sections(const std::string& key) {
  YAML::Node n;
  std::vector<YamlSection> items;
  if (!take(key, n)) return items;
  if (!n.IsSequence()) fail(key, "expected a list of maps");
  for (std::size_t i = 0; i < n.size(); ++i)
    items.emplace_back(n[i], file_, qualified(key) + "[" + std::to_string(i) + "]");
  return items;
}

void YamlSection::finish() const {
  if (!node_ || !node_.IsMap()) return;
  std::set<std::string> seen;
  for (const auto& item : node_) {
    if (!item.first.IsScalar()) {
      throw InputError(file_ + ":" + line_of(item.first) + " a key under '" +
                       (path_.empty() ? "<top>" : path_) + "' is not a plain name");
    }
    const std::string key = item.first.Scalar();
    // yaml-cpp keeps both entries of a repeated key and node[key] finds the first: refuse it
    // rather than silently ignore the second value.
    if (!seen.insert(key).second) {
      throw InputError(file_ + ":" + line_of(item.first) + " duplicate key '" + qualified(key) +
                       "'");
    }
    if (!used_.count(key)) {
      throw InputError(file_ + ":" + line_of(item.first) + " unknown key '" + qualified(key) + "'");
    }
  }
}

YAML::Node load_yaml_file(const std::string& path) {
  return parse_yaml(read_file(path), path);
}

YAML::Node parse_yaml(const std::string& text, const std::string& name) {
  // yaml-cpp parses recursively; refuse absurd nesting before it can overflow the stack. Flow
  // brackets count outside comments and quoted scalars ("# range [0, 1)" opens nothing); a quote
  // opens a scalar only where one can start (after ": ", "- ", a flow bracket or comma, or at a
  // line's start), so the apostrophe of "model: don't care" is text.
  constexpr int kMaxDepth = 64;
  int depth = 0;
  char quote = 0;    // ' or " while inside a quoted scalar
  char last = '\n';  // the last character outside spaces on this line
  for (std::size_t i = 0; i < text.size(); ++i) {
    const char c = text[i];
    if (quote) {
      if (c == '\\' && quote == '"')
        ++i;  // an escaped character
      else if (c == quote)
        quote = 0;
      last = c;
      continue;
    }
    const bool space = c == ' ' || c == '\t';
    if (c == '#' && (i == 0 || std::isspace(static_cast<unsigned char>(text[i - 1])))) {
      while (i + 1 < text.size() && text[i + 1] != '\n')
        ++i;
      continue;
    }
    if ((c == '\'' || c == '"') && std::strchr("\n:-[{,", last) != nullptr) {
      quote = c;
    } else if (c == '[' || c == '{') {
      if (++depth > kMaxDepth) throw InputError(name + ": YAML nested too deeply");
    } else if ((c == ']' || c == '}') && depth > 0) {
      --depth;
    }
    if (!space) last = c;
  }
  YAML::Node document;
  try {
    // A second document ('---') was ignored without a word; an empty one (a closing '---', or
    // one before the content) says nothing.
    if (count_documents(text) > 1)
      throw InputError(name +
                       ": holds more than one YAML document (separated by '---'); one is "
                       "expected");
    for (const YAML::Node& d : YAML::LoadAll(text))  // ends: count_documents got through
      if (!d.IsNull()) document = d;
  } catch (const YAML::DeepRecursion&) {  // yaml-cpp's own guard ("bad file")
    throw InputError(name + ": YAML nested too deeply");
  } catch (const YAML::Exception& e) {
    throw InputError(name + ":" + std::to_string(e.mark.line + 1) +
                     ": YAML syntax error: " + e.msg);
  }
  return document;
}
}  // namespace jpcr
