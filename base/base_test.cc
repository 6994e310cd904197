#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <stdexcept>
#include <vector>

#include "base/binary_reader.h"
#include "base/error.h"
#include "base/file_util.h"
#include "base/large_buffer.h"
#include "base/parallel_for.h"
#include "base/subprocess.h"
#include "base/text_reader.h"

namespace ms {
namespace {

namespace fs = std::filesystem;

TEST(Subprocess, AppendsOutputToTheLogAndReportsTheExit) {
  const std::filesystem::path log =
      std::filesystem::temp_directory_path() / ("ms_subprocess_" + std::to_string(getpid()));
  std::filesystem::remove(log);
  SubprocessOptions child;
  child.executable = "/bin/sh";
  child.argv = {"sh", "-c", "echo out; echo err >&2; echo \"$MS_TEST_VALUE\"; exit 3"};
  child.env = {"MS_TEST_VALUE=given"};
  child.output_path = log.string();
  child.stdin_from_null = true;
  int status = 0;
  ASSERT_TRUE(WaitForExit(StartSubprocess(child), 30, &status));
  EXPECT_EQ(DescribeExit(status), "exit code 3");
  std::ifstream in(log);
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  EXPECT_EQ(text, "out\nerr\ngiven\n");
  child.executable = "/nonexistent/program";
  ASSERT_TRUE(WaitForExit(StartSubprocess(child), 30, &status));
  EXPECT_EQ(DescribeExit(status), "exit code 127");
  child.output_path = "/nonexistent/folder/log";
  EXPECT_THROW(StartSubprocess(child), InternalError);
  std::filesystem::remove(log);
}

TEST(LargeBuffer, ReusesFreedBlocksOfTheSameSizeAndStartsZeroed) {
  large_buffer::ReleaseCache();
  const size_t n = (large_buffer::kMinHugeBytes / sizeof(float)) + 12345;
  const float* first = nullptr;
  {
    LargeBuffer<float> a(n, 0.0f);
    first = a.data();
    std::fill(a.begin(), a.end(), 7.0f);
  }
  EXPECT_GE(large_buffer::CachedBytes(), n * sizeof(float));
  LargeBuffer<float> b(n);
  EXPECT_EQ(b.data(), first) << "the freed block is reused";
  EXPECT_EQ(std::count(b.begin(), b.end(), 0.0f), static_cast<std::ptrdiff_t>(n));
  EXPECT_EQ(large_buffer::CachedBytes(), 0u);
  // A block the cache has no size for comes from the system; small ones never enter the cache.
  {
    LargeBuffer<float> c(2 * n);
    EXPECT_NE(c.data(), first);
    { LargeBuffer<int> small(100, 1); }
    EXPECT_EQ(large_buffer::CachedBytes(), 0u);
  }
  // Freed, c is kept (b and c were both alive: the peak holds them), and what the cache holds
  // with what is in use never passes that peak: b's block, freed too, fits beside c's.
  EXPECT_GE(large_buffer::CachedBytes(), 2 * n * sizeof(float));
  b = LargeBuffer<float>();
  const size_t both = large_buffer::CachedBytes();
  EXPECT_GE(both, 3 * n * sizeof(float));
  // A block freed past the peak goes back to the system: the cache already holds b and c, so
  // one larger than both is not kept beside them.
  { LargeBuffer<float> larger(8 * n); }
  EXPECT_EQ(large_buffer::CachedBytes(), both);
  large_buffer::ReleaseCache();
  EXPECT_EQ(large_buffer::CachedBytes(), 0u);
}

TEST(ParallelFor, RunsEveryIndexOnce) {
  std::vector<int> runs(1000, 0);
  ParallelFor(
      runs.size(), [&](size_t i) { ++runs[i]; }, 4);
  EXPECT_EQ(std::count(runs.begin(), runs.end(), 1), 1000);
  ParallelFor(0, [](size_t) { FAIL(); });
}

TEST(ParallelFor, RethrowsTheErrorOfTheSmallestIndexLikeASequentialLoop) {
  for (int threads : {1, 2, 8}) {
    try {
      ParallelFor(
          200,
          [](size_t i) {
            if (i % 50 == 17) throw std::runtime_error("item " + std::to_string(i));
          },
          threads);
      FAIL() << "nothing thrown";
    } catch (const std::runtime_error& e) {
      EXPECT_STREQ(e.what(), "item 17");
    }
  }
}

TEST(TextReader, ReportsFileLineAndField) {
  TextReader reader("points.txt", "# comment\n\n1 2 x\n");
  std::string_view line = reader.RequireDataLine("a point");
  auto fields = SplitFields(line);
  ASSERT_EQ(fields.size(), 3u);
  EXPECT_EQ(reader.ParseInt(fields[0], "id"), 1);
  try {
    reader.ParseDouble(fields[2], "X");
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_STREQ(e.what(), "points.txt:3: X: 'x' is not a number");
  }
}

TEST(TextReader, TokenLineNumbers) {
  TextReader reader("t", "a b\n\nc\nd");
  reader.NextToken("a");
  EXPECT_EQ(reader.line_number(), 1);
  reader.NextToken("b");
  EXPECT_EQ(reader.line_number(), 1);
  reader.NextToken("c");
  EXPECT_EQ(reader.line_number(), 3);
  EXPECT_FALSE(reader.AtEnd());
  EXPECT_EQ(reader.line_number(), 4);
  // Lines then tokens: the token after line 1 is on line 2.
  TextReader mixed("m", "header\n7 8\n");
  std::string_view line;
  ASSERT_TRUE(mixed.NextLine(&line));
  EXPECT_EQ(mixed.line_number(), 1);
  mixed.NextToken("seven");
  EXPECT_EQ(mixed.line_number(), 2);
  mixed.NextToken("eight");
  try {
    mixed.NextToken("nine");
    FAIL();
  } catch (const InputError& e) {
    EXPECT_STREQ(e.what(), "m:2: unexpected end of file, expected nine");
  }
}

TEST(TextReader, RejectsNonFiniteAndOutOfRange) {
  TextReader reader("f", "nan inf -5 99999999999999999999");
  EXPECT_THROW(reader.NextDouble("a"), InputError);
  EXPECT_THROW(reader.NextDouble("b"), InputError);
  EXPECT_THROW(reader.NextInt("c", 0, 10), InputError);
  EXPECT_THROW(reader.NextInt("d"), InputError);
  EXPECT_TRUE(reader.AtEnd());
  EXPECT_THROW(reader.NextToken("e"), InputError);
}

TEST(BinaryReader, TruncationAndHugeCounts) {
  const char bytes[6] = {1, 0, 0, 0, 2, 0};
  BinaryReader reader("x.bin", bytes, sizeof(bytes));
  EXPECT_EQ(reader.Read<uint32_t>("n"), 1u);
  EXPECT_THROW(reader.Read<uint32_t>("m"), InputError);
  EXPECT_THROW(reader.CheckCount(uint64_t{1} << 40, 8, "points"), InputError);
  EXPECT_NO_THROW(reader.CheckCount(1, 2, "points"));
}

TEST(AtomicFileWriter, LeavesNothingWhenNotCommitted) {
  const fs::path dir = fs::temp_directory_path() / "ms_base_test";
  fs::create_directories(dir);
  const fs::path target = dir / "out.txt";
  fs::remove(target);
  {
    AtomicFileWriter writer(target);
    writer.stream() << "partial";
  }
  EXPECT_FALSE(fs::exists(target));
  WriteFileAtomically(target, [](std::ostream& out) { out << "complete"; });
  EXPECT_EQ(ReadFileToString(target), "complete");
  EXPECT_THROW(ReadFileToString(target, 3), InputError);
  fs::remove_all(dir);
}

}  // namespace
}  // namespace ms
