#include "tvf/core/json_text.h"

#include "tvf/core/error.h"
#include "support/test_paths.h"

#include <gtest/gtest.h>

#include <string>

namespace tvf {
namespace {

using test::error_of;

TEST(JsonText, ReadsOneThousandLevelsAndRefusesTheNext) {
  const std::string ok = std::string(kMaxJsonDepth, '[') + std::string(kMaxJsonDepth, ']');
  nlohmann::json j = parse_json_text(ok, "t");
  for (size_t depth = 1; depth < kMaxJsonDepth; ++depth) {
    ASSERT_TRUE(j.is_array() && j.size() == 1) << depth;
    j = nlohmann::json(j[0]);
  }
  EXPECT_EQ(j, nlohmann::json::array());
  const std::string deep = "\n  {\"a\": [" + std::string(kMaxJsonDepth, '[');
  EXPECT_EQ(error_of([&] { parse_json_text(deep, "t"); }),
            "t: line 2, column 1008: arrays and objects nest more than 1000 deep, more than tvf reads");
  // Brackets inside strings do not count.
  EXPECT_NO_THROW(parse_json_text("[\"" + std::string(5000, '[') + "\"]", "t"));
}

TEST(JsonText, RefusesNulBytesRepeatedKeysAndEmptyText) {
  EXPECT_EQ(error_of([] { parse_json_text(std::string("{}\0{}", 5), "t"); }),
            "t: line 1, column 3: the text contains a NUL byte, which JSON text cannot (write \\u0000 inside a string)");
  EXPECT_EQ(error_of([] { parse_json_text(R"({"a": [1, {"b": 1, "b": 2}]})", "t"); }),
            "t: a[1].b: the key appears twice in the same object (JSON keys must be unique)");
  EXPECT_EQ(error_of([] { parse_json_text(" \n", "t", "give an object"); }), "t: the text is empty; give an object");
  // A string of a megabyte in a syntax error is not quoted whole.
  EXPECT_LT(error_of([] { parse_json_text("[\"" + std::string(1 << 20, 'x') + "\" 1]", "t"); }).size(), 300u);
}

TEST(JsonText, FindsTheLineAndColumnOfAJsonPath) {
  const std::string text =
      "{\"tvf\": 1,\n"
      " \"a\": {\"b\": [10, {\"c\": \"x]}\"}, [7, 8]],\n"
      "       \"d\\\"e\": null, \"d\": true},\n"
      " \"\u00e9\": 0, \"z\": 5}";
  auto at = [&](const std::string& path) {
    const JsonTextPosition p = json_path_position(text, path);
    return std::pair(p.line, p.column);
  };
  EXPECT_EQ(at(""), std::pair(1, 1));
  EXPECT_EQ(at("tvf"), std::pair(1, 9));
  EXPECT_EQ(at("a"), std::pair(2, 7));
  EXPECT_EQ(at("a.b"), std::pair(2, 13));
  EXPECT_EQ(at("a.b[0]"), std::pair(2, 14));
  EXPECT_EQ(at("a.b[1].c"), std::pair(2, 24));  // a bracket inside a string is text
  EXPECT_EQ(at("a.b[2][1]"), std::pair(2, 36));
  EXPECT_EQ(at("a.d"), std::pair(3, 27));       // not the key with an escaped quote
  EXPECT_EQ(at("z"), std::pair(4, 15));         // columns count code points (é is one)
  EXPECT_EQ(at("a.b[3]"), std::pair(0, 0));     // no such value
  EXPECT_EQ(at("a.x"), std::pair(0, 0));
  EXPECT_EQ(at("tvf.x"), std::pair(0, 0));
  EXPECT_EQ(at("a..b"), std::pair(0, 0));       // not a path tvf writes
}

TEST(JsonText, ErrorsCarryTheirPlaceAsFields) {
  try {
    parse_json_text("{\"a\": 1,\n \"b\": [1, 2,, 3]}", "f.json");
    FAIL() << "no error";
  } catch (const Error& e) {
    EXPECT_EQ(location_of(e).file, "f.json");
    EXPECT_EQ(location_of(e).line, 2);
    EXPECT_EQ(location_of(e).column, 13);
    EXPECT_EQ(std::string(e.what()).rfind("f.json: line 2, column 13: ", 0), 0u) << e.what();
  }
  // A value's error found after parsing gets its line and column from the text.
  const std::string text = "{\"time\": {\n  \"frames\": -3}}";
  try {
    try {
      throw_input_error("s.json", "time.frames", "must be at least 2, got -3");
    } catch (const Error& e) {
      EXPECT_EQ(location_of(e).json_path, "time.frames");
      EXPECT_EQ(location_of(e).line, 0);
      rethrow_with_position(e, text);
    }
  } catch (const Error& e) {
    EXPECT_STREQ(e.what(), "s.json: time.frames: must be at least 2, got -3");  // unchanged
    EXPECT_EQ(location_of(e).file, "s.json");
    EXPECT_EQ(location_of(e).json_path, "time.frames");
    EXPECT_EQ(location_of(e).line, 2);
    EXPECT_EQ(location_of(e).column, 13);
  }
}

TEST(JsonText, ReadsFilesUpToALimit) {
  test::TempDir dir;
  test::write_text(dir / "a.json", "[1, 2]");
  EXPECT_EQ(read_text_file((dir / "a.json").string(), "the file", 6), "[1, 2]");
  EXPECT_EQ(error_of([&] { read_text_file((dir / "a.json").string(), "the file", 5); }),
            "cannot read the file '" + (dir / "a.json").string() + "': it is longer than 5 bytes, the limit for a "
            "JSON file");
}

// Error messages are valid UTF-8 (the bytes that are not written as \xNN), so that JSON
// answers can always hold them.
TEST(ValidUtf8, KeepsWellFormedText) {
  EXPECT_EQ(valid_utf8(""), "");
  EXPECT_EQ(valid_utf8("plain text 123"), "plain text 123");
  EXPECT_EQ(valid_utf8("d\xC3\xA9j\xC3\xA0 \xE2\x80\x94 \xF0\x9F\x98\x80"), "d\xC3\xA9j\xC3\xA0 \xE2\x80\x94 \xF0\x9F\x98\x80");
  EXPECT_EQ(valid_utf8("\xF4\x8F\xBF\xBF"), "\xF4\x8F\xBF\xBF");  // U+10FFFF, the last code point
}

TEST(ValidUtf8, WritesEveryOtherByteAsHex) {
  EXPECT_EQ(valid_utf8("1\xFF\xFF 0"), "1\\xFF\\xFF 0");
  EXPECT_EQ(valid_utf8("\xC0\xAF"), "\\xC0\\xAF");              // overlong '/'
  EXPECT_EQ(valid_utf8("\xE2\x82"), "\\xE2\\x82");              // cut short at the end
  EXPECT_EQ(valid_utf8("\xE2\x82x"), "\\xE2\\x82x");            // cut short before ASCII
  EXPECT_EQ(valid_utf8("\xED\xA0\x80"), "\\xED\\xA0\\x80");     // a surrogate
  EXPECT_EQ(valid_utf8("\xF4\x90\x80\x80"), "\\xF4\\x90\\x80\\x80");  // above U+10FFFF
  EXPECT_EQ(valid_utf8("\x80\xC3\xA9"), "\\x80\xC3\xA9");       // a lone continuation byte
}

// A mesh word with bytes 0xFF (found by fuzz_session: the server's status and error
// answers could not be serialised).
TEST(ValidUtf8, InputErrorsCanGoIntoJson) {
  try {
    throw_input_error("m.off", "", "line 5: OFF vertex 1: '1\xFF\xFF' is not a number");
    FAIL() << "no error thrown";
  } catch (const Error& e) {
    EXPECT_STREQ(e.what(), "m.off: line 5: OFF vertex 1: '1\\xFF\\xFF' is not a number");
    EXPECT_EQ(nlohmann::json({{"error", e.what()}}).dump(),
              R"({"error":"m.off: line 5: OFF vertex 1: '1\\xFF\\xFF' is not a number"})");
  }
}

}  // namespace
}  // namespace tvf
