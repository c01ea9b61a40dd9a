#include "fploc/core/text_out.h"

#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

using fploc::json_text;
using fploc::printable;

TEST(Printable, ControlBytesAndBytesThatAreNotUtf8AreEscaped) {
  EXPECT_EQ(printable("/scan_front"), "/scan_front");
  EXPECT_EQ(printable("/imu\x1b[2J"), "/imu\\x1b[2J");                  // a terminal escape
  EXPECT_EQ(printable(std::string("a\0b\n\x7f", 5)), "a\\x00b\\x0a\\x7f");
  EXPECT_EQ(printable("/imu\xe9"), "/imu\\xe9");                        // Latin-1
  EXPECT_EQ(printable("W\xc3\xa4nde"), "W\xc3\xa4nde");                 // UTF-8 stays
  EXPECT_EQ(printable("\xe2\x82\xac \xf0\x9f\x99\x82"), "\xe2\x82\xac \xf0\x9f\x99\x82");
  EXPECT_EQ(printable("x\xc2\x9b" "31m"), "x\\xc2\\x9b31m");           // U+009B, the 8-bit CSI
  EXPECT_EQ(printable("\xc0\xaf"), "\\xc0\\xaf");                        // overlong '/'
  EXPECT_EQ(printable("\xed\xa0\x80"), "\\xed\\xa0\\x80");              // a surrogate
  EXPECT_EQ(printable("\xe2\x82"), "\\xe2\\x82");                        // cut sequence
  EXPECT_EQ(printable("a\\b"), "a\\x5cb");                               // unambiguous
}

TEST(JsonText, BytesThatAreNotUtf8BecomeReplacementCharacters) {
  const nlohmann::json j = {{"file", "/tmp/r\xe9sum\xe9.lcm"}, {"n", 3}};
  EXPECT_THROW((void)j.dump(), nlohmann::json::type_error);  // what the tools did
  EXPECT_EQ(json_text(j), "{\"file\":\"/tmp/r\xef\xbf\xbdsum\xef\xbf\xbd.lcm\",\"n\":3}");
  EXPECT_EQ(nlohmann::json::parse(json_text(j, 2)).at("n"), 3);
  const nlohmann::json k = {{"a", 1}, {"b", "x"}};
  EXPECT_EQ(json_text(k, 1), k.dump(1));  // otherwise dump's text
}
