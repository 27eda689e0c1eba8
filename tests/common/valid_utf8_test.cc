#include "server/common/valid_utf8.h"

#include <string>

#include <gtest/gtest.h>

namespace vpm {
namespace {

TEST(ValidUtf8, KeepsValidTextAsItIs) {
  for (const std::string& text : {std::string(""), std::string("CT ABDOMEN"),
                                  std::string("Sch\xc3\xa4"
                                              "del"),                          // ä, 2 bytes
                                  std::string("\xe2\x82\xac 3"),               // €, 3 bytes
                                  std::string("\xf0\x9f\xa9\xbb"),             // U+1FA7B, 4 bytes
                                  std::string("\xe5\xb1\xb1\xe7\x94\xb0")}) {  // 山田
    EXPECT_TRUE(IsValidUtf8(text)) << text;
    EXPECT_EQ(ValidUtf8(text), text);
  }
}

TEST(ValidUtf8, ReadsWhatIsNotUtf8AsLatin1) {
  // ISO 8859-1 as a scanner without SpecificCharacterSet writes it.
  EXPECT_FALSE(IsValidUtf8("M\xfcller^J\xf6rg"));
  EXPECT_EQ(ValidUtf8("M\xfcller^J\xf6rg"), "M\xc3\xbcller^J\xc3\xb6rg");  // Müller^Jörg
  // Valid sequences beside invalid bytes are kept.
  EXPECT_EQ(ValidUtf8("\xc3\xa4\xe4"), "\xc3\xa4\xc3\xa4");
}

TEST(ValidUtf8, RefusesMalformedSequencesByteByByte) {
  const std::string bad[] = {
      std::string("\x80"),              // a lone continuation byte
      std::string("\xc3"),              // truncated at the end
      std::string("\xe2\x82"),          // truncated
      std::string("\xc0\xaf"),          // overlong '/'
      std::string("\xe0\x80\xaf"),      // overlong, 3 bytes
      std::string("\xed\xa0\x80"),      // a surrogate, U+D800
      std::string("\xf4\x90\x80\x80"),  // over U+10FFFF
      std::string("\xff"),
  };
  for (const std::string& text : bad) {
    EXPECT_FALSE(IsValidUtf8(text));
    const std::string fixed = ValidUtf8(text);
    EXPECT_TRUE(IsValidUtf8(fixed));
    EXPECT_EQ(fixed.size(), 2 * text.size()) << "each byte one Latin-1 character";
  }
}

TEST(IsAscii, IsFalseForAnyByteFrom0x80) {
  EXPECT_TRUE(IsAscii(""));
  EXPECT_TRUE(IsAscii("DOE^JANE 1.2.3\x7f"));
  EXPECT_FALSE(IsAscii("M\xc3\xbcller"));  // UTF-8
  EXPECT_FALSE(IsAscii("M\xfcller"));      // Latin-1
}

}  // namespace
}  // namespace vpm
