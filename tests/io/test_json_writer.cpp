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
