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

TEST(JsonText, ReadsFilesUpToALimit) {
  test::TempDir dir;
  test::write_text(dir / "a.json", "[1, 2]");
  EXPECT_EQ(read_text_file((dir / "a.json").string(), "the file", 6), "[1, 2]");
  EXPECT_EQ(error_of([&] { read_text_file((dir / "a.json").string(), "the file", 5); }),
            "cannot read the file '" + (dir / "a.json").string() + "': it is longer than 5 bytes, the limit for a "
            "JSON file");
}

}  // namespace
}  // namespace tvf
