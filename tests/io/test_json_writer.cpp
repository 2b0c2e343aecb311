#include <sstream>

#include <gtest/gtest.h>

#include "jpcr/io/json_writer.hpp"

namespace jpcr {
namespace {

TEST(JsonWriter, NestedStructureAndEscapes) {
  std::ostringstream out;
  JsonWriter json(out, 0);
  json.begin_object();
  json.field("name", "a\"b\\c\n");
  json.field("n", 3);
  json.field("x", 0.1);
  json.field("bad", std::numeric_limits<double>::quiet_NaN());
  json.field("ok", true);
  json.key("list").begin_array().value(1).value(2.5).end_array();
  json.field("v", std::vector<double>{1.0, std::numeric_limits<double>::infinity()});
  json.key("empty").begin_object().end_object();
  json.end_object();
  EXPECT_EQ(out.str(),
            "{\"name\":\"a\\\"b\\\\c\\n\",\"n\":3,\"x\":0.1,\"bad\":null,\"ok\":true,"
            "\"list\":[1,2.5],\"v\":[1, null],\"empty\":{}}");
}

// JSON is UTF-8: well-formed sequences pass, any other byte (a Latin-1 path, a cut sequence, an
// overlong form, a surrogate) becomes U+FFFD.
TEST(JsonWriter, BytesThatAreNotUtf8BecomeTheReplacementCharacter) {
  const auto escaped = [](const std::string& s) { return JsonWriter::escape(s); };
  EXPECT_EQ(escaped("caf\xc3\xa9 \xe2\x82\xac \xf0\x9f\x99\x82"),
            "caf\xc3\xa9 \xe2\x82\xac \xf0\x9f\x99\x82");
  EXPECT_EQ(escaped("dir\xff/x"), "dir\\ufffd/x");
  EXPECT_EQ(escaped("caf\xe9"), "caf\\ufffd");                  // Latin-1
  EXPECT_EQ(escaped("\xe2\x82"), "\\ufffd\\ufffd");             // cut short
  EXPECT_EQ(escaped("\xc0\xaf"), "\\ufffd\\ufffd");             // overlong '/'
  EXPECT_EQ(escaped("\xed\xa0\x80"), "\\ufffd\\ufffd\\ufffd");  // a surrogate
}

TEST(JsonWriter, PythonParsesIndentedOutput) {
  std::ostringstream out;
  JsonWriter json(out);
  json.begin_object().field("a", 1).key("b").begin_array().value("x").end_array().end_object();
  const std::string text = out.str();
  EXPECT_NE(text.find("\n  \"a\": 1"), std::string::npos);
  if (std::system("/usr/bin/python3 -c 'import json' 2>/dev/null") != 0) GTEST_SKIP();
  const std::string cmd = "printf '%s' '" + text +
                          "' | /usr/bin/python3 -c 'import json,sys; "
                          "d=json.load(sys.stdin); assert d[\"b\"]==[\"x\"]'";
  EXPECT_EQ(std::system(cmd.c_str()), 0);
}

}  // namespace
}  // namespace jpcr
