#include "proto/content_hash.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>

#include "base/error.h"

namespace ms {
namespace {

// Reference vectors of XXH64 with seed 0 (xxHash's own and python-xxhash's documentation).
TEST(Xxh64, MatchesReferenceVectors) {
  EXPECT_EQ(HashBytes(""), 0xEF46DB3751D8E999ull);
  EXPECT_EQ(HashBytes("a"), 0xD24EC4F1A98C6E5Bull);
  EXPECT_EQ(HashBytes("abc"), 0x44BC2CF5AD770999ull);
  // 39 and 43 bytes: the 32-byte stripe loop, then the 8/4/1-byte tails.
  EXPECT_EQ(HashBytes("Nobody inspects the spammish repetition"), 0xFBCEA83C8A378BF1ull);
  EXPECT_EQ(HashBytes("The quick brown fox jumps over the lazy dog"), 0x0B242D361FDA71BCull);
}

TEST(Xxh64, IncrementalEqualsOneShotForEverySplit) {
  std::string data;
  for (int i = 0; i < 300; ++i) data.push_back(static_cast<char>((i * 131 + 7) & 0xff));
  const uint64_t expected = HashBytes(data);
  for (size_t split = 0; split <= data.size(); split += 7) {
    Xxh64 state;
    state.Update(data.data(), split);
    state.Update(data.data() + split, data.size() - split);
    EXPECT_EQ(state.Digest(), expected) << "split " << split;
  }
  Xxh64 bytewise;
  for (char c : data) bytewise.Update(&c, 1);
  EXPECT_EQ(bytewise.Digest(), expected);
  data[150] ^= 1;
  EXPECT_NE(HashBytes(data), expected);
}

TEST(HashFile, HashesContentsAndNamesMissingFiles) {
  const std::string path = ::testing::TempDir() + "/hash_me.bin";
  std::string data(3'000'000, 'x');
  for (size_t i = 0; i < data.size(); i += 97) data[i] = static_cast<char>(i & 0xff);
  std::ofstream(path, std::ios::binary) << data;
  const FileHash hash = HashFile(path);
  EXPECT_EQ(hash.size, data.size());
  EXPECT_EQ(hash.hash, HashBytes(data));
  EXPECT_EQ(HashHex(0xEF46DB3751D8E999ull), "ef46db3751d8e999");
  try {
    HashFile(path + ".missing");
    FAIL() << "no exception";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("hash_me.bin.missing"), std::string::npos);
  }
  std::filesystem::remove(path);
}

}  // namespace
}  // namespace ms
