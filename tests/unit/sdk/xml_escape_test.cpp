#include <plr/xml_escape.hpp>

#include <gtest/gtest.h>

namespace {

TEST(XmlEscape, EscapesTheFiveSpecialCharacters) {
  EXPECT_EQ(plr::xml_escape("A1 <seed 1> & \"B\" 'c'"),
            "A1 &lt;seed 1&gt; &amp; &quot;B&quot; &apos;c&apos;");
  EXPECT_EQ(plr::xml_escape("plain"), "plain");
  EXPECT_EQ(plr::xml_escape(""), "");
}

}  // namespace
