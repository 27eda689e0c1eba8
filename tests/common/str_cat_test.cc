#include <cstdint>
#include <string>
#include <string_view>

#include <gtest/gtest.h>

#include "server/common/status.h"

namespace vpm {
namespace {

TEST(StrCat, JoinsStringsViewsAndNumbers) {
  const std::string_view view = "view";
  EXPECT_EQ(StrCat("a", std::string("b"), view, 3, " ", 2.5, " ", -1.0e-7), "abview3 2.5 -1e-07");
}

TEST(StrCat, OneByteIntegersPrintAsNumbersAndCharsAsCharacters) {
  const uint8_t u = 200;
  const int8_t s = -5;
  EXPECT_EQ(StrCat(u, ",", s, ",", 'x'), "200,-5,x");
}

TEST(StrAppend, AppendsToTheText) {
  std::string text = "dims=";
  StrAppend(&text, 4, "x", 5);
  EXPECT_EQ(text, "dims=4x5");
}

}  // namespace
}  // namespace vpm
