#include "shaders/shaders.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "base/error.h"

namespace ms::shaders {
namespace {

TEST(Shaders, EmbeddedSourcesAreTheFiles) {
  const std::string_view source = Source("mesh_depth.frag");
  EXPECT_EQ(source.substr(0, 9), "#version ");
  EXPECT_THAT(std::string(source), ::testing::HasSubstr("gl_PrimitiveID"));
  EXPECT_TRUE(Has("surface.frag"));
  EXPECT_FALSE(Has("missing.frag"));
  const std::vector<std::string_view> names = Names();
  EXPECT_TRUE(std::is_sorted(names.begin(), names.end()));
  EXPECT_THAT(names, ::testing::Contains("noise.glsl"));
}

TEST(Shaders, UnknownNameThrowsListingKnownOnes) {
  try {
    Source("nope.vert");
    FAIL();
  } catch (const InternalError& e) {
    EXPECT_THAT(e.what(), ::testing::HasSubstr("nope.vert"));
    EXPECT_THAT(e.what(), ::testing::HasSubstr("mesh_depth.vert"));
  }
}

TEST(Shaders, ExpandInsertsIncludesWithLineDirectives) {
  std::vector<std::string> names;
  const std::string expanded = Expand("surface.frag", &names);
  ASSERT_EQ(names.size(), 2u);
  EXPECT_EQ(names[0], "surface.frag");
  EXPECT_EQ(names[1], "noise.glsl");
  EXPECT_THAT(expanded, ::testing::HasSubstr("float ms_fbm("));
  EXPECT_THAT(expanded, ::testing::HasSubstr("#line 1 1\n"));
  EXPECT_THAT(expanded, ::testing::Not(::testing::HasSubstr("\n#include")));
  // The main file resumes at the line after the #include.
  const std::string source(Source("surface.frag"));
  const size_t include = source.find("#include");
  const int include_line =
      1 + static_cast<int>(std::count(source.begin(), source.begin() + include, '\n'));
  EXPECT_THAT(expanded, ::testing::HasSubstr("#line " + std::to_string(include_line + 1) + " 0\n"));
}

}  // namespace
}  // namespace ms::shaders
