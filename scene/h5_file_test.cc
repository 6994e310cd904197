#include "scene/h5_file.h"

#include <H5Cpp.h>
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <limits>
#include <random>

#include "base/error.h"
#include "base/file_util.h"
#include "testing/testing.h"

namespace fs = std::filesystem;
using ::testing::HasSubstr;

namespace ms {
namespace {

class H5FileTest : public ::testing::Test {
 protected:
  std::string Path(const std::string& name) const { return dir_ / name; }

  testing::TempDir dir_{"h5_file"};
};

using testing::ExpectInputError;

template <typename T>
bool BitwiseEqual(const std::vector<T>& a, const std::vector<T>& b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(T)) == 0;
}

void WriteBytes(const std::string& path, const std::string& bytes) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
}

TEST_F(H5FileTest, EveryTypeRoundTripsExactly) {
  const std::string path = Path("sub/dir/all.h5");  // parent directories are created
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const std::vector<double> doubles = {1.0 / 3, -0.0,  nan, std::numeric_limits<double>::infinity(),
                                       1e-310,  1e308, 2.5, -7,
                                       0.1,     0.2,   0.3, 42};
  const std::vector<float> floats = {std::nanf("0x123"), -0.0f, 1e-40f, 3.25f};
  const std::vector<int32_t> int32s = {std::numeric_limits<int32_t>::min(), -1, 0,
                                       std::numeric_limits<int32_t>::max()};
  const std::vector<int64_t> int64s = {std::numeric_limits<int64_t>::min(), 0,
                                       std::numeric_limits<int64_t>::max()};
  std::vector<uint8_t> bytes(256);
  for (int i = 0; i < 256; ++i) bytes[i] = static_cast<uint8_t>(i);
  const std::vector<std::string> strings = {"", "a.png", "Ünïcødé/ß.jpg", std::string(3000, 'x')};
  {
    H5File file = H5File::Create(path);
    EXPECT_TRUE(file.writable());
    file.Write("/numbers/doubles", doubles, {3, 4});
    file.Write("numbers/floats", floats);
    file.Write("/numbers/int32", int32s, {2, 2});
    file.Write("/numbers/int64", int64s);
    file.Write("/bytes", bytes, {2, 8, 16});
    file.Write("/strings", strings, {2, 2});
    file.Write("/empty", std::vector<double>{}, {0, 3});
    file.Write("/empty_strings", std::vector<std::string>{});
    file.CreateGroup("/a/b/c");
    file.CreateGroup("/a/b");  // existing: fine
    file.SetIntAttribute("/", "version", -12345678901234);
    file.SetDoubleAttribute("/numbers/doubles", "scale", 1.0 / 7);
    file.SetStringAttribute("/a/b", "note", "héllo");
    file.SetStringAttribute("/a/b", "note", "replaced");
    // Not visible under the final name until Commit().
    EXPECT_FALSE(fs::exists(path));
    EXPECT_TRUE(fs::exists(TempPathFor(path)));
    file.Commit();
    EXPECT_FALSE(file.is_open());
  }
  EXPECT_TRUE(fs::exists(path));
  EXPECT_FALSE(fs::exists(TempPathFor(path)));

  const H5File file = H5File::OpenReadOnly(path);
  EXPECT_FALSE(file.writable());
  H5Shape shape;
  EXPECT_TRUE(BitwiseEqual(file.Read<double>("/numbers/doubles", {3, 4}, &shape), doubles));
  EXPECT_EQ(shape, (H5Shape{3, 4}));
  EXPECT_TRUE(BitwiseEqual(file.Read<float>("/numbers/floats", {kH5Any}), floats));
  EXPECT_EQ(file.Read<int32_t>("/numbers/int32", {2, kH5Any}), int32s);
  EXPECT_EQ(file.Read<int64_t>("/numbers/int64", {3}), int64s);
  EXPECT_EQ(file.Read<uint8_t>("/bytes", {2, 8, 16}), bytes);
  EXPECT_EQ(file.Read<std::string>("/strings", {2, 2}), strings);
  EXPECT_TRUE(file.Read<double>("/empty", {0, 3}).empty());
  EXPECT_TRUE(file.Read<std::string>("/empty_strings", {0}).empty());
  EXPECT_EQ(file.ReadIntAttribute("/", "version"), -12345678901234);
  EXPECT_EQ(file.ReadDoubleAttribute("numbers/doubles", "scale"), 1.0 / 7);
  EXPECT_EQ(file.ReadStringAttribute("/a/b", "note"), "replaced");
  EXPECT_TRUE(file.HasAttribute("/a/b", "note"));
  EXPECT_FALSE(file.HasAttribute("/a/b", "other"));
  EXPECT_FALSE(file.HasAttribute("/missing", "note"));

  EXPECT_EQ(file.List("/"), (std::vector<std::string>{"a", "bytes", "empty", "empty_strings",
                                                      "numbers", "strings"}));
  EXPECT_EQ(file.List("/numbers"),
            (std::vector<std::string>{"doubles", "floats", "int32", "int64"}));
  EXPECT_TRUE(file.Exists("/a/b/c"));
  EXPECT_TRUE(file.IsGroup("/a/b/c"));
  EXPECT_FALSE(file.IsDataset("/a/b/c"));
  EXPECT_TRUE(file.IsDataset("/bytes"));
  EXPECT_FALSE(file.Exists("/nope/deeper"));
  EXPECT_FALSE(file.Exists("/bytes/inside_a_dataset"));  // a dataset as a parent: just false

  const H5DatasetInfo info = file.Info("/bytes");
  EXPECT_EQ(info.type, H5Type::kUInt8);
  EXPECT_EQ(info.shape, (H5Shape{2, 8, 16}));
  EXPECT_EQ(info.num_elements, 256u);
  EXPECT_FALSE(info.chunked);
  EXPECT_EQ(file.Info("/strings").type, H5Type::kString);
  EXPECT_EQ(file.Info("/numbers/floats").type, H5Type::kFloat32);
  EXPECT_EQ(file.Info("/numbers/int32").type, H5Type::kInt32);
}

// Files of other writers: h5py writes variable-length strings (UTF-8 for str, ASCII for bytes)
// and numpy's fixed-width bytes; Fortran-style tools pad with spaces.
TEST_F(H5FileTest, ReadsForeignStringLayouts) {
  const std::string path = Path("foreign.h5");
  {
    H5::Exception::dontPrint();
    H5::H5File file(path, H5F_ACC_TRUNC);
    const hsize_t two[1] = {2};
    for (const H5T_cset_t cset : {H5T_CSET_UTF8, H5T_CSET_ASCII}) {
      H5::StrType type(H5::PredType::C_S1, H5T_VARIABLE);
      type.setCset(cset);
      const char* values[2] = {cset == H5T_CSET_UTF8 ? "ünï" : "plain", ""};
      const std::string name = cset == H5T_CSET_UTF8 ? "vlen_utf8" : "vlen_ascii";
      file.createDataSet(name, type, H5::DataSpace(1, two)).write(values, type);
      file.createAttribute(name, type, H5::DataSpace(H5S_SCALAR)).write(type, &values[0]);
    }
    H5::StrType spaced(H5::PredType::C_S1, 6);
    spaced.setStrpad(H5T_STR_SPACEPAD);
    file.createDataSet("spaced", spaced, H5::DataSpace(1, two)).write("ab    cdef  ", spaced);
    H5::StrType terminated(H5::PredType::C_S1, 4);
    terminated.setStrpad(H5T_STR_NULLTERM);
    file.createDataSet("terminated", terminated, H5::DataSpace(1, two))
        .write("ab\0\0abc\0", terminated);
  }
  const H5File file = H5File::OpenReadOnly(path);
  EXPECT_EQ(file.Read<std::string>("/vlen_utf8", {2}), (std::vector<std::string>{"ünï", ""}));
  EXPECT_EQ(file.Read<std::string>("/vlen_ascii", {2}), (std::vector<std::string>{"plain", ""}));
  EXPECT_EQ(file.ReadStringAttribute("/", "vlen_utf8"), "ünï");
  EXPECT_EQ(file.ReadStringAttribute("/", "vlen_ascii"), "plain");
  EXPECT_EQ(file.Read<std::string>("/spaced", {2}), (std::vector<std::string>{"ab", "cdef"}));
  EXPECT_EQ(file.Read<std::string>("/terminated", {2}), (std::vector<std::string>{"ab", "abc"}));
}

TEST_F(H5FileTest, UncommittedCreateLeavesNothing) {
  const std::string path = Path("never.h5");
  {
    H5File file = H5File::Create(path);
    file.Write("/x", std::vector<double>{1, 2, 3});
  }
  EXPECT_FALSE(fs::exists(path));
  EXPECT_FALSE(fs::exists(TempPathFor(path)));
  {
    H5File file = H5File::Create(path);
    file.Close();  // explicit discard
  }
  EXPECT_FALSE(fs::exists(path));
  EXPECT_FALSE(fs::exists(TempPathFor(path)));
}

TEST_F(H5FileTest, LargeArraysAreChunkedAndCompressed) {
  const std::string path = Path("large.h5");
  std::vector<double> smooth(300000);
  for (size_t i = 0; i < smooth.size(); ++i) smooth[i] = std::floor(i / 1000.0);
  std::mt19937_64 rng(7);
  std::vector<double> noise(3 * 50000);
  for (double& v : noise) v = std::uniform_real_distribution<double>(-1, 1)(rng);
  {
    H5File file = H5File::Create(path);
    file.Write("/smooth", smooth);
    file.Write("/noise", noise, {50000, 3});
    file.Write("/small", std::vector<double>(100, 1.0));
    file.Commit();
  }
  const H5File file = H5File::OpenReadOnly(path);
  const H5DatasetInfo info = file.Info("/smooth");
  EXPECT_TRUE(info.chunked);
  EXPECT_TRUE(info.compressed);
  EXPECT_FALSE(info.extendible);
  EXPECT_TRUE(file.Info("/noise").chunked);
  EXPECT_FALSE(file.Info("/small").chunked);
  EXPECT_TRUE(BitwiseEqual(file.Read<double>("/smooth", {kH5Any}), smooth));
  EXPECT_TRUE(BitwiseEqual(file.Read<double>("/noise", {50000, 3}), noise));
  // 2.4 MB of smooth doubles compress to almost nothing; the noise barely compresses.
  const uint64_t raw = (smooth.size() + noise.size()) * sizeof(double);
  EXPECT_LT(fs::file_size(path), raw / 2 + 100000);
}

TEST_F(H5FileTest, ReadsCheckShapeAndTypeAndWidenLosslessly) {
  const std::string path = Path("types.h5");
  {
    H5File file = H5File::Create(path);
    file.Write("/d", std::vector<double>{1, 2, 3, 4}, {2, 2});
    file.Write("/f", std::vector<float>{1.5f, -2.25f});
    file.Write("/i32", std::vector<int32_t>{-5, 7});
    file.Write("/i64", std::vector<int64_t>{1, 2});
    file.Write("/u8", std::vector<uint8_t>{200, 255});
    file.Write("/s", std::vector<std::string>{"x"});
    file.Commit();
  }
  const H5File file = H5File::OpenReadOnly(path);
  // Lossless widening.
  EXPECT_EQ(file.Read<double>("/f", {2}), (std::vector<double>{1.5, -2.25}));
  EXPECT_EQ(file.Read<int64_t>("/i32", {2}), (std::vector<int64_t>{-5, 7}));
  EXPECT_EQ(file.Read<int32_t>("/u8", {2}), (std::vector<int32_t>{200, 255}));
  // Shape mismatches name the dataset and both shapes.
  ExpectInputError([&] { file.Read<double>("/d", {4}); },
                   {path, "/d", "has shape (2, 2), expected (4,)"});
  ExpectInputError([&] { file.Read<double>("/d", {2, 3}); }, {path, "/d", "expected (2, 3)"});
  // Narrowing and kind changes are refused.
  ExpectInputError(
      [&] {
        file.Read<float>("/d", {2, 2});
      },
      {path, "/d", "stored as float64", "as float32"});
  ExpectInputError([&] { file.Read<int32_t>("/i64", {2}); }, {path, "/i64", "int64"});
  ExpectInputError([&] { file.Read<uint8_t>("/i32", {2}); }, {path, "/i32"});
  ExpectInputError([&] { file.Read<double>("/i32", {2}); }, {path, "/i32"});
  ExpectInputError([&] { file.Read<std::string>("/d", {2, 2}); }, {path, "/d"});
  ExpectInputError([&] { file.Read<double>("/s", {1}); }, {path, "/s", "string"});
  // Missing things.
  ExpectInputError([&] { file.Read<double>("/missing/x", {kH5Any}); },
                   {path, "/missing/x", "not found"});
  ExpectInputError([&] { file.Read<double>("/", {kH5Any}); }, {path, "is not a dataset"});
  ExpectInputError([&] { file.Info("/nothing"); }, {path, "/nothing"});
  ExpectInputError([&] { file.List("/d"); }, {path, "/d", "not a group"});
  ExpectInputError([&] { file.ReadIntAttribute("/d", "absent"); },
                   {path, "/d", "attribute 'absent' not found"});
  ExpectInputError([&] { file.Read<double>("/a/../d", {kH5Any}); }, {path, "not allowed"});
}

TEST_F(H5FileTest, AttributeTypesAreChecked) {
  const std::string path = Path("attrs.h5");
  {
    H5File file = H5File::Create(path);
    file.SetStringAttribute("/", "s", "text");
    file.SetDoubleAttribute("/", "d", 2.5);
    file.SetIntAttribute("/", "i", 3);
    file.Commit();
  }
  const H5File file = H5File::OpenReadOnly(path);
  ExpectInputError([&] { file.ReadIntAttribute("/", "s"); }, {path, "'s'", "expected an integer"});
  ExpectInputError([&] { file.ReadIntAttribute("/", "d"); }, {path, "'d'"});
  ExpectInputError([&] { file.ReadDoubleAttribute("/", "i"); }, {path, "'i'"});
  ExpectInputError([&] { file.ReadStringAttribute("/", "i"); }, {path, "expected a string"});
}

TEST_F(H5FileTest, WriteReplacesDatasetsAndRefusesGroups) {
  const std::string path = Path("replace.h5");
  H5File file = H5File::Create(path);
  file.Write("/x", std::vector<double>{1, 2, 3});
  file.Write("/x", std::vector<int32_t>{4, 5});
  EXPECT_EQ(file.Read<int32_t>("/x", {2}), (std::vector<int32_t>{4, 5}));
  file.CreateGroup("/g");
  ExpectInputError([&] { file.Write("/g", std::vector<double>{1}); },
                   {path, "/g", "not a dataset"});
  ExpectInputError([&] { file.CreateGroup("/x"); }, {path, "/x", "not a group"});
  ExpectInputError([&] { file.Write("/s", std::vector<std::string>{std::string("a\0b", 3)}); },
                   {path, "/s", "NUL"});
  file.Commit();
}

TEST_F(H5FileTest, CopyFromCarriesAGroupWhole) {
  const std::string source_path = Path("source.h5"), copy_path = Path("copy.h5");
  {
    H5File source = H5File::Create(source_path);
    source.Write("/scene/points/position", std::vector<double>{1, 2, 3, 4, 5, 6}, H5Shape{2, 3});
    source.Write("/scene/views/name", std::vector<std::string>{"a.jpg", "b.jpg"});
    source.SetIntAttribute("/scene", "version", 7);
    source.Write("/other", std::vector<int32_t>{1});
    source.Commit();
  }
  const H5File source = H5File::OpenReadOnly(source_path);
  H5File copy = H5File::Create(copy_path);
  copy.CopyFrom(source, "scene");
  ExpectInputError([&] { copy.CopyFrom(source, "/scene"); }, {copy_path, "/scene", "exists"});
  ExpectInputError([&] { copy.CopyFrom(source, "/missing"); },
                   {source_path, "/missing", "not found"});
  copy.Commit();
  const H5File read = H5File::OpenReadOnly(copy_path);
  EXPECT_EQ(read.Read<double>("/scene/points/position", {2, 3}),
            (std::vector<double>{1, 2, 3, 4, 5, 6}));
  EXPECT_EQ(read.Read<std::string>("/scene/views/name", {2}),
            (std::vector<std::string>{"a.jpg", "b.jpg"}));
  EXPECT_EQ(read.ReadIntAttribute("/scene", "version"), 7);
  EXPECT_FALSE(read.Exists("/other"));
}

TEST_F(H5FileTest, TablesAppendAcrossReopen) {
  const std::string path = Path("stats.h5");
  const std::vector<H5Column> columns = {{"iteration", H5Type::kInt64},
                                         {"time_s", H5Type::kFloat64},
                                         {"ratio", H5Type::kFloat32},
                                         {"faces", H5Type::kInt32},
                                         {"phase", H5Type::kString}};
  {
    H5File file = H5File::Create(path, [] {
      H5FileOptions options;
      options.table_chunk_rows = 2;  // several chunks with few rows
      return options;
    }());
    file.CreateTable("/stats", columns);
    EXPECT_EQ(file.NumRows("/stats"), 0u);
    EXPECT_TRUE(file.Info("/stats/time_s").extendible);
    for (int64_t i = 0; i < 3; ++i) {
      file.AppendRow("/stats", {i, 0.5 * i, 0.25f, int32_t(10 * i), std::string("grow")});
    }
    file.Commit();
  }
  for (int session = 0; session < 2; ++session) {  // the coordinator reopens per iteration
    H5File file = H5File::OpenReadWrite(path);
    const int64_t i = static_cast<int64_t>(file.NumRows("stats"));
    // int32 widens to int64 and float to double.
    file.AppendRow("stats", {int32_t(i), 0.5f * i, 0.25f, int32_t(10 * i),
                             std::string(session ? "shrink" : "")});
    file.Flush();
    file.Close();
  }
  const H5File file = H5File::OpenReadOnly(path);
  EXPECT_EQ(file.TableColumns("/stats"), columns);
  EXPECT_EQ(file.NumRows("/stats"), 5u);
  EXPECT_EQ(file.ReadColumn<int64_t>("/stats", "iteration"), (std::vector<int64_t>{0, 1, 2, 3, 4}));
  EXPECT_EQ(file.ReadColumn<double>("/stats", "time_s"), (std::vector<double>{0, 0.5, 1, 1.5, 2}));
  EXPECT_EQ(file.ReadColumn<int32_t>("/stats", "faces"), (std::vector<int32_t>{0, 10, 20, 30, 40}));
  EXPECT_EQ(file.ReadColumn<std::string>("/stats", "phase"),
            (std::vector<std::string>{"grow", "grow", "grow", "", "shrink"}));
  EXPECT_EQ(file.Read<float>("/stats/ratio", {5}), std::vector<float>(5, 0.25f));
  ExpectInputError([&] { file.ReadColumn<double>("/stats", "nope"); }, {path, "no column 'nope'"});
}

TEST_F(H5FileTest, BadRowsChangeNothing) {
  const std::string path = Path("badrows.h5");
  H5File file = H5File::Create(path);
  file.CreateTable("/t", {{"a", H5Type::kInt32}, {"b", H5Type::kFloat32}});
  file.AppendRow("/t", {int32_t(1), 1.0f});
  // Narrowing (double -> float32), wrong kind, wrong count: rejected before any write.
  ExpectInputError(
      [&] {
        file.AppendRow("/t", {int32_t(2), 2.0});
      },
      {path, "/t", "column 'b' is float32, got a float64"});
  ExpectInputError([&] { file.AppendRow("/t", {std::string("x"), 1.0f}); }, {path, "column 'a'"});
  ExpectInputError([&] { file.AppendRow("/t", {int32_t(2)}); }, {path, "1 values for 2 columns"});
  EXPECT_EQ(file.NumRows("/t"), 1u);
  ExpectInputError(
      [&] {
        file.CreateTable("/t", {{"a", H5Type::kInt32}});
      },
      {path, "/t", "already exists"});
  ExpectInputError(
      [&] {
        file.CreateTable("/u", {{"bad,name", H5Type::kInt32}});
      },
      {path, "bad column name"});
  ExpectInputError(
      [&] {
        file.CreateTable("/u", {{"a", H5Type::kInt32}, {"a", H5Type::kInt64}});
      },
      {path, "duplicate column 'a'"});
  // Columns of different lengths (an interrupted append) are reported, not misread.
  file.Write("/t/b", std::vector<float>{1, 2, 3});
  ExpectInputError([&] { file.NumRows("/t"); }, {path, "/t", "different lengths"});
  ExpectInputError([&] { file.TableColumns("/"); }, {path, "not a table"});
  file.Commit();
}

TEST_F(H5FileTest, BrokenFilesGiveCleanErrors) {
  const std::string good = Path("good.h5");
  {
    H5File file = H5File::Create(good);
    std::vector<double> values(20000);
    for (size_t i = 0; i < values.size(); ++i) values[i] = std::sin(i);
    file.Write("/values", values);
    file.Commit();
  }
  const std::string bytes = ReadFileToString(good);

  const std::string missing = Path("missing.h5");
  ExpectInputError([&] { H5File::OpenReadOnly(missing); }, {missing, "not found"});
  const std::string text = Path("text.h5");
  WriteBytes(text, "this is not an HDF5 file\n");
  ExpectInputError([&] { H5File::OpenReadOnly(text); }, {text, "not an HDF5 file"});
  const std::string empty = Path("empty.h5");
  WriteBytes(empty, "");
  ExpectInputError([&] { H5File::OpenReadOnly(empty); }, {empty, "not an HDF5 file"});

  // Cut at several places: the header, inside the data, just before the end.
  for (size_t cut : {size_t{16}, size_t{600}, bytes.size() / 2, bytes.size() - 1}) {
    const std::string truncated = Path("truncated_" + std::to_string(cut) + ".h5");
    WriteBytes(truncated, bytes.substr(0, cut));
    ExpectInputError(
        [&] {
          const H5File file = H5File::OpenReadOnly(truncated);
          file.Read<double>("/values", {kH5Any});
        },
        {truncated});
  }

  // HDF5's own error printing stays off.
  ::testing::internal::CaptureStderr();
  EXPECT_THROW(H5File::OpenReadOnly(text), InputError);
  const std::string truncated = Path("truncated_600.h5");
  EXPECT_THROW(H5File::OpenReadOnly(truncated), InputError);
  EXPECT_EQ(::testing::internal::GetCapturedStderr(), "");
}

TEST_F(H5FileTest, MetadataCorruptionIsDetected) {
  // Superblock and object headers are checksummed (HDF5 1.8 format): flipping any byte of the
  // first few hundred bytes (superblock, root group) must be caught, never misread.
  const std::string good = Path("good.h5");
  {
    H5File file = H5File::Create(good);
    file.Write("/values", std::vector<int32_t>{1, 2, 3});
    file.SetStringAttribute("/values", "unit", "m");
    file.Commit();
  }
  const std::string bytes = ReadFileToString(good);
  int detected = 0, tried = 0;
  for (size_t offset = 0; offset < std::min<size_t>(bytes.size(), 400); offset += 3) {
    std::string corrupt = bytes;
    corrupt[offset] = static_cast<char>(corrupt[offset] ^ 0x5a);
    const std::string path = Path("corrupt.h5");
    WriteBytes(path, corrupt);
    ++tried;
    try {
      const H5File file = H5File::OpenReadOnly(path);
      const std::vector<int32_t> values = file.Read<int32_t>("/values", {3});
      file.ReadStringAttribute("/values", "unit");
      // Reaching here means the byte was not used (padding, unused space): data must be intact.
      EXPECT_EQ(values, (std::vector<int32_t>{1, 2, 3})) << "offset " << offset;
    } catch (const InputError& e) {
      EXPECT_THAT(e.what(), HasSubstr(path));
      ++detected;
    }
  }
  EXPECT_GT(detected, tried / 2);
}

// A file that legitimately declares enormous datasets but stores no data for them (HDF5
// allocates lazily), as a corrupt or hostile file could: reading must refuse, not allocate.
TEST_F(H5FileTest, HugeClaimedDatasetIsRefusedBeforeAllocating) {
  const std::string path = Path("huge.h5");
  {
    H5::Exception::dontPrint();
    H5::H5File file(path, H5F_ACC_TRUNC);
    // Under the default 16 GiB read limit: caught by the check against the stored bytes.
    const hsize_t gib[1] = {hsize_t{1} << 30};
    const H5::DataSpace space(1, gib);
    file.createDataSet("contiguous", H5::PredType::IEEE_F64LE, space);
    H5::DSetCreatPropList dcpl;
    const hsize_t chunk[1] = {1 << 16};
    dcpl.setChunk(1, chunk);
    dcpl.setDeflate(6);
    file.createDataSet("compressed", H5::PredType::IEEE_F64LE, space, dcpl);
    H5::DSetCreatPropList plain;
    plain.setChunk(1, chunk);
    file.createDataSet("chunked", H5::PredType::STD_U8LE, space, plain);
    const hsize_t strings_dims[1] = {hsize_t{1} << 28};
    file.createDataSet("strings", H5::StrType(H5::PredType::C_S1, H5T_VARIABLE),
                       H5::DataSpace(1, strings_dims));
    // 2^40 elements: over the read limit.
    const hsize_t tera[1] = {hsize_t{1} << 40};
    file.createDataSet("tera", H5::PredType::IEEE_F64LE, H5::DataSpace(1, tera));
  }
  ASSERT_LT(fs::file_size(path), 100000u);
  const H5File file = H5File::OpenReadOnly(path);
  EXPECT_EQ(file.Info("/tera").num_elements, uint64_t{1} << 40);
  ExpectInputError([&] { file.Read<double>("/contiguous", {kH5Any}); },
                   {path, "/contiguous", "claims shape (1073741824,)", "holds 0 bytes"});
  ExpectInputError([&] { file.Read<double>("/compressed", {kH5Any}); },
                   {path, "/compressed", "holds 0 bytes"});
  ExpectInputError([&] { file.Read<uint8_t>("/chunked", {kH5Any}); },
                   {path, "/chunked", "holds 0 bytes"});
  ExpectInputError([&] { file.Read<std::string>("/strings", {kH5Any}); },
                   {path, "/strings", "holds 0 bytes"});
  ExpectInputError([&] { file.Read<double>("/tera", {kH5Any}); },
                   {path, "/tera", "claims shape (1099511627776,)", "read limit"});

  // The same for a real dataset larger than a configured read limit.
  const std::string small = Path("limit.h5");
  {
    H5File out = H5File::Create(small);
    out.Write("/x", std::vector<double>(1000, 1.0));
    out.Commit();
  }
  H5FileOptions options;
  options.max_read_bytes = 4000;
  const H5File limited = H5File::OpenReadOnly(small, options);
  ExpectInputError([&] { limited.Read<double>("/x", {kH5Any}); }, {small, "/x", "read limit"});
}

// Old-format files (no metadata checksums), as other tools write them: a dataspace patched to
// claim 2^40 elements must still end in a clean error.
TEST_F(H5FileTest, PatchedDataspaceIsRefused) {
  const std::string path = Path("patched.h5");
  const uint64_t marker = 0x1D2B3C4DULL;  // the extent, easy to find in the bytes
  {
    H5::Exception::dontPrint();
    H5::H5File file(path, H5F_ACC_TRUNC);  // default: earliest format, no checksums
    const hsize_t dims[1] = {marker};
    H5::DSetCreatPropList dcpl;
    const hsize_t chunk[1] = {1 << 16};
    dcpl.setChunk(1, chunk);
    dcpl.setDeflate(1);
    std::vector<uint8_t> data(marker % 100000, 7);  // not the full extent: small file
    const hsize_t data_dims[1] = {data.size()};
    H5::DataSet small =
        file.createDataSet("small", H5::PredType::STD_U8LE, H5::DataSpace(1, data_dims));
    small.write(data.data(), H5::PredType::NATIVE_UINT8);
    file.createDataSet("lazy", H5::PredType::STD_U8LE, H5::DataSpace(1, dims), dcpl);
  }
  std::string bytes = ReadFileToString(path);
  char pattern[8];
  std::memcpy(pattern, &marker, 8);
  const uint64_t huge = uint64_t{1} << 40;
  char replacement[8];
  std::memcpy(replacement, &huge, 8);
  int patched = 0;
  for (size_t at = bytes.find(std::string(pattern, 8)); at != std::string::npos;
       at = bytes.find(std::string(pattern, 8), at + 8)) {
    bytes.replace(at, 8, replacement, 8);
    ++patched;
  }
  ASSERT_GT(patched, 0);
  // And the small dataset's extent, grown 10^5-fold without its storage.
  const uint64_t small_extent = marker % 100000;
  std::memcpy(pattern, &small_extent, 8);
  const uint64_t small_huge = small_extent * 100000ULL;
  std::memcpy(replacement, &small_huge, 8);
  const size_t small_at = bytes.find(std::string(pattern, 8));
  ASSERT_NE(small_at, std::string::npos);
  bytes.replace(small_at, 8, replacement, 8);
  WriteBytes(path, bytes);

  ExpectInputError(
      [&] {
        const H5File file = H5File::OpenReadOnly(path);
        file.Read<uint8_t>("/lazy", {kH5Any});
      },
      {path});
  ExpectInputError(
      [&] {
        const H5File file = H5File::OpenReadOnly(path);
        file.Read<uint8_t>("/small", {kH5Any});
      },
      {path});
}

TEST(H5FileOptionsTest, CheckNamesTheField) {
  H5FileOptions options;
  EXPECT_NO_THROW(options.Check());
  options.deflate_level = 12;
  ExpectInputError([&] { options.Check(); }, {"deflate_level"});
  options = {};
  options.chunk_bytes = 10;
  ExpectInputError([&] { options.Check(); }, {"chunk_bytes"});
  options = {};
  options.table_chunk_rows = 0;
  ExpectInputError([&] { options.Check(); }, {"table_chunk_rows"});
}

TEST(H5FileHelpersTest, JoinAndShapes) {
  EXPECT_EQ(H5Join("/", "views"), "/views");
  EXPECT_EQ(H5Join("/ckpt/", "/scene"), "/ckpt/scene");
  EXPECT_EQ(H5Join("ckpt", "views/R"), "ckpt/views/R");
  EXPECT_EQ(H5ShapeString({3}), "(3,)");
  EXPECT_EQ(H5ShapeString({kH5Any, 3}), "(any, 3)");
  EXPECT_EQ(H5TypeName(H5Type::kUInt8), "uint8");
}

}  // namespace
}  // namespace ms
