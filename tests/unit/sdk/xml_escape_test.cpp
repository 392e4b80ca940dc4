#include <plr/xml_escape.hpp>

#include <gtest/gtest.h>

namespace {

TEST(XmlEscape, EscapesWhatBreaksAnElementOrADoubleQuotedAttribute) {
  EXPECT_EQ(plr::xml_escape("A1 <seed 1> & \"B\" H's"),
            "A1 &lt;seed 1&gt; &amp; &quot;B&quot; H's");
  EXPECT_EQ(plr::xml_escape("plain"), "plain");
  EXPECT_EQ(plr::xml_escape(""), "");
}

}  // namespace
