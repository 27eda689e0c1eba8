#include "server/pacs/multipart_parser.h"

#include <gtest/gtest.h>

#include <string>
#include <vector>

namespace vpm::pacs {
namespace {

struct Parsed {
  std::vector<std::string> parts;
  std::vector<MultipartParser::Headers> headers;
  Status fed;
  Status finished;
};

// Feeds `body` in chunks of `chunk` bytes (every split point is tried by
// the callers that loop over chunk sizes).
Parsed Parse(const std::string& boundary, const std::string& body, size_t chunk) {
  Parsed out;
  MultipartParser parser(boundary, {
                                       .part_begin =
                                           [&](const MultipartParser::Headers& h) {
                                             out.headers.push_back(h);
                                             out.parts.emplace_back();
                                             return absl::OkStatus();
                                           },
                                       .part_data =
                                           [&](std::string_view data) {
                                             out.parts.back().append(data);
                                             return absl::OkStatus();
                                           },
                                       .part_end = nullptr,
                                   });
  for (size_t at = 0; at < body.size() && out.fed.ok(); at += chunk) {
    out.fed = parser.Feed(std::string_view(body).substr(at, chunk));
  }
  if (out.fed.ok()) out.finished = parser.Finish();
  return out;
}

std::string Body(const std::string& boundary, const std::vector<std::string>& parts,
                 bool with_length) {
  std::string body;
  for (const std::string& p : parts) {
    body += "--" + boundary + "\r\nContent-Type: application/dicom\r\n";
    if (with_length) body += "Content-Length: " + std::to_string(p.size()) + "\r\n";
    body += "\r\n" + p + "\r\n";
  }
  return body + "--" + boundary + "--\r\n";
}

TEST(MultipartBoundary, QuotedAndUnquoted) {
  EXPECT_EQ(*MultipartBoundary("multipart/related; type=\"application/dicom\"; boundary=abc123"),
            "abc123");
  EXPECT_EQ(*MultipartBoundary("Multipart/Related;boundary=\"a b;c\"; type=application/dicom"),
            "a b;c");
  EXPECT_EQ(*MultipartBoundary("multipart/related; BOUNDARY=  xyz  ;type=x"), "xyz");
  EXPECT_EQ(*MultipartBoundary("multipart/related; boundary=\"q\\\"x\""), "q\"x");
}

TEST(MultipartBoundary, RejectsOtherTypesAndMissingBoundary) {
  EXPECT_TRUE(absl::IsInvalidArgument(MultipartBoundary("application/dicom+json").status()));
  EXPECT_TRUE(absl::IsInvalidArgument(MultipartBoundary("multipart/related; type=x").status()));
  EXPECT_TRUE(absl::IsInvalidArgument(MultipartBoundary("multipart/related; boundary=").status()));
  EXPECT_TRUE(
      absl::IsInvalidArgument(MultipartBoundary("multipart/related; boundary=\"ab").status()));
  EXPECT_TRUE(absl::IsInvalidArgument(
      MultipartBoundary("multipart/related; boundary=" + std::string(201, 'b')).status()));
}

TEST(MultipartParser, SplitsPartsAtEveryChunkSize) {
  // Part bytes that contain CR, LF, "--" and a near-boundary.
  const std::vector<std::string> parts = {"DICM\r\n--abc\r\nxx", std::string(1000, '\0') + "end",
                                          "\r\n", "last--"};
  const std::string body = Body("abcd", parts, true);
  for (size_t chunk : {1, 2, 3, 5, 7, 64, 4096}) {
    Parsed p = Parse("abcd", body, chunk);
    ASSERT_TRUE(p.fed.ok()) << chunk << ": " << p.fed;
    ASSERT_TRUE(p.finished.ok()) << chunk << ": " << p.finished;
    ASSERT_EQ(p.parts, parts) << "chunk " << chunk;
    EXPECT_EQ(p.headers[0].at("content-type"), "application/dicom");
  }
}

TEST(MultipartParser, IgnoresPartContentLengthThatLies) {
  // The per-part Content-Length says 3, the part holds 11 bytes: the
  // boundary decides.
  const std::string body =
      "--b\r\nContent-Length: 3\r\n\r\nhello world\r\n--b\r\n\r\nsecond\r\n--b--";
  Parsed p = Parse("b", body, 4);
  ASSERT_TRUE(p.finished.ok()) << p.finished;
  ASSERT_EQ(p.parts.size(), 2u);
  EXPECT_EQ(p.parts[0], "hello world");
  EXPECT_EQ(p.parts[1], "second");  // a part without headers
}

TEST(MultipartParser, SkipsPreambleAndEpilogue) {
  const std::string body = "this is a preamble\r\n--b\r\n\r\nx\r\n--b--\r\nepilogue --b\r\n";
  Parsed p = Parse("b", body, 3);
  ASSERT_TRUE(p.finished.ok()) << p.finished;
  ASSERT_EQ(p.parts, std::vector<std::string>{"x"});
}

TEST(MultipartParser, AcceptsPaddingAfterBoundary) {
  Parsed p = Parse("b", "--b  \t\r\n\r\nx\r\n--b--", 1);
  ASSERT_TRUE(p.finished.ok()) << p.finished;
  EXPECT_EQ(p.parts, std::vector<std::string>{"x"});
}

TEST(MultipartParser, RejectsTruncatedBodies) {
  const std::string body = Body("bnd", {"first part", "second part"}, false);
  // Every cut short of the closing delimiter is an error.
  const size_t close = body.rfind("--bnd--");
  for (size_t cut = 0; cut < close + 6; ++cut) {
    Parsed p = Parse("bnd", body.substr(0, cut), 5);
    EXPECT_FALSE(p.fed.ok() && p.finished.ok()) << "cut at " << cut;
    if (p.fed.ok()) {
      EXPECT_TRUE(absl::IsInvalidArgument(p.finished)) << cut;
    }
  }
  Parsed cut = Parse("bnd", body.substr(0, body.find("second") + 3), 5);
  EXPECT_NE(cut.finished.message().find("truncated"), std::string_view::npos) << cut.finished;
}

TEST(MultipartParser, RejectsMalformedInput) {
  EXPECT_TRUE(absl::IsInvalidArgument(Parse("b", "no boundary here", 4).finished));
  // Junk right after a boundary instead of a line end.
  EXPECT_TRUE(absl::IsInvalidArgument(Parse("b", "--bjunk\r\n\r\nx\r\n--b--", 4).fed));
  // A header line without a colon.
  EXPECT_TRUE(absl::IsInvalidArgument(Parse("b", "--b\r\nnot a header\r\n\r\nx\r\n--b--", 4).fed));
  // Endless headers.
  const std::string huge = "--b\r\nX: " + std::string(MultipartParser::kMaxHeaderBytes + 10, 'a');
  EXPECT_TRUE(absl::IsInvalidArgument(Parse("b", huge, 1000).fed));
  // A wrong boundary is no boundary at all.
  EXPECT_TRUE(absl::IsInvalidArgument(Parse("other", Body("b", {"x"}, true), 7).finished));
}

TEST(MultipartParser, PassesCallbackErrorsThrough) {
  MultipartParser parser(
      "b", {.part_begin = nullptr,
            .part_data = [](std::string_view) { return absl::ResourceExhaustedError("too big"); },
            .part_end = nullptr});
  Status fed = parser.Feed("--b\r\n\r\n" + std::string(100, 'x'));
  EXPECT_TRUE(absl::IsResourceExhausted(fed)) << fed;
}

TEST(MultipartParser, CountsEmptyBodyOfPartsAsZeroParts) {
  Parsed p = Parse("b", "--b--\r\n", 2);
  EXPECT_TRUE(p.finished.ok());
  EXPECT_TRUE(p.parts.empty());
}

}  // namespace
}  // namespace vpm::pacs
