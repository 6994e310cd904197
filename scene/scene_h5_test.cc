#include "scene/scene_h5.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iostream>
#include <limits>
#include <random>

#include "base/error.h"
#include "base/file_util.h"
#include "scene/h5_file.h"
#include "scene/scene_io.h"
#include "testing/testing.h"

namespace fs = std::filesystem;
using ::testing::HasSubstr;

namespace ms {
namespace {

class SceneH5Test : public ::testing::Test {
 protected:
  std::string Path(const std::string& name) const { return dir_ / name; }

  testing::TempDir dir_{"scene_h5"};
};

using testing::ExpectInputError;

template <typename T>
bool SameBits(const T& a, const T& b) {
  return std::memcmp(&a, &b, sizeof(T)) == 0;
}

// A scene exercising everything the format stores: distortion, names with odd characters,
// missing image paths, NaN pixel coordinates (with a payload), long tracks, untracked points.
Scene RandomScene(int num_views, int num_points, int max_track, uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> unit(-1, 1);
  Scene scene;
  scene.source = "random.nvm";
  for (int i = 0; i < num_views; ++i) {
    View v;
    v.name = "img_" + std::to_string(i) + (i % 3 == 0 ? " é,ü.png" : ".jpg");
    v.image_path = i % 4 == 0 ? "" : "/data/images/" + v.name;
    v.intrinsics.width = 640 + 16 * i;
    v.intrinsics.height = 480 + 8 * i;
    v.intrinsics.fx = 500 + 100 * unit(rng);
    v.intrinsics.fy = v.intrinsics.fx * (1 + 1e-3 * unit(rng));
    v.intrinsics.cx = v.intrinsics.width / 2.0 + unit(rng);
    v.intrinsics.cy = v.intrinsics.height / 2.0 + unit(rng);
    if (i % 2 == 0) {
      v.intrinsics.k1 = 0.1 * unit(rng);
      v.intrinsics.k2 = 0.01 * unit(rng);
      v.intrinsics.p1 = 1e-3 * unit(rng);
      v.intrinsics.p2 = 1e-3 * unit(rng);
      v.intrinsics.k3 = 1e-4 * unit(rng);
    }
    v.R = RotationFromQuaternion(1 + unit(rng), unit(rng), unit(rng), unit(rng));
    v.SetCenter({5 * unit(rng), 5 * unit(rng), -10 + unit(rng)});
    scene.views.push_back(v);
  }
  const float nan_payload = std::nanf("0x2a");
  for (int i = 0; i < num_points; ++i) {
    ScenePoint p;
    p.position = {unit(rng), unit(rng), unit(rng)};
    p.color = {static_cast<uint8_t>(rng()), static_cast<uint8_t>(rng()),
               static_cast<uint8_t>(rng())};
    const int track = num_views == 0 ? 0 : static_cast<int>(rng() % (max_track + 1));
    for (int view = 0; view < num_views && static_cast<int>(p.observations.size()) < track;
         ++view) {
      if (rng() % 2) continue;
      Observation o;
      o.view = view;
      o.x = i % 5 == 0 ? nan_payload : static_cast<float>(640 * (unit(rng) + 1) / 2);
      o.y = i % 5 == 0 ? std::numeric_limits<float>::quiet_NaN()
                       : static_cast<float>(1e-3 * unit(rng));
      p.observations.push_back(o);
    }
    scene.points.push_back(p);
  }
  return scene;
}

// Bit-for-bit comparison of everything but `source`.
void ExpectIdentical(const Scene& a, const Scene& b) {
  ASSERT_EQ(a.views.size(), b.views.size());
  for (size_t i = 0; i < a.views.size(); ++i) {
    const View& u = a.views[i];
    const View& v = b.views[i];
    EXPECT_EQ(u.name, v.name);
    EXPECT_EQ(u.image_path, v.image_path);
    EXPECT_EQ(u.intrinsics.width, v.intrinsics.width);
    EXPECT_EQ(u.intrinsics.height, v.intrinsics.height);
    EXPECT_TRUE(SameBits(u.intrinsics, v.intrinsics)) << "view " << i;
    EXPECT_TRUE(SameBits(u.R, v.R)) << "view " << i;
    EXPECT_TRUE(SameBits(u.t, v.t)) << "view " << i;
  }
  ASSERT_EQ(a.points.size(), b.points.size());
  for (size_t i = 0; i < a.points.size(); ++i) {
    const ScenePoint& p = a.points[i];
    const ScenePoint& q = b.points[i];
    EXPECT_TRUE(SameBits(p.position, q.position)) << "point " << i;
    EXPECT_EQ(p.color, q.color);
    ASSERT_EQ(p.observations.size(), q.observations.size()) << "point " << i;
    for (size_t j = 0; j < p.observations.size(); ++j) {
      EXPECT_EQ(p.observations[j].view, q.observations[j].view);
      EXPECT_TRUE(SameBits(p.observations[j].x, q.observations[j].x)) << "point " << i;
      EXPECT_TRUE(SameBits(p.observations[j].y, q.observations[j].y)) << "point " << i;
    }
  }
}

TEST_F(SceneH5Test, RandomSceneRoundTripsBitForBit) {
  const Scene scene = RandomScene(9, 700, 6, 1);
  ASSERT_NO_THROW(scene.Validate());
  const std::string path = Path("scene.h5");
  WriteSceneH5(scene, path);
  EXPECT_FALSE(fs::exists(TempPathFor(path)));
  const Scene read = ReadSceneH5(path);
  ExpectIdentical(scene, read);
  EXPECT_EQ(read.source, path);
  EXPECT_EQ(read.Summary(), scene.Summary());
  const H5File file = H5File::OpenReadOnly(path);
  EXPECT_EQ(ReadSceneH5Source(file, "/"), "random.nvm");
  EXPECT_EQ(file.ReadIntAttribute("/", "format_version"), kSceneH5FormatVersion);
}

TEST_F(SceneH5Test, EmptyAndDegenerateScenes) {
  for (const auto& [views, points] : {std::pair{0, 0}, std::pair{3, 0}, std::pair{0, 5}}) {
    const Scene scene = RandomScene(views, points, 3, 2);
    const std::string path =
        Path("s" + std::to_string(views) + "_" + std::to_string(points) + ".h5");
    WriteSceneH5(scene, path);
    ExpectIdentical(scene, ReadSceneH5(path));
  }
}

TEST_F(SceneH5Test, ManyObservationsAreCompressedAndExact) {
  const Scene scene = RandomScene(40, 30000, 12, 3);
  ASSERT_GT(scene.NumObservations(), 100000u);
  const std::string path = Path("big.h5");
  WriteSceneH5(scene, path);
  ExpectIdentical(scene, ReadSceneH5(path));
  const H5File file = H5File::OpenReadOnly(path);
  EXPECT_TRUE(file.Info("/observations/view").compressed);
  EXPECT_TRUE(file.Info("/points/position").chunked);
}

TEST_F(SceneH5Test, SceneInsideAGroupBesideOtherData) {
  const Scene scene = RandomScene(4, 50, 4, 4);
  const std::string path = Path("checkpoint.h5");
  {
    H5File file = H5File::Create(path);
    file.CreateTable("/stats", {{"iteration", H5Type::kInt64}});
    file.AppendRow("/stats", {int64_t{17}});
    WriteSceneH5(scene, file, "/checkpoint/scene");
    file.Write("/checkpoint/extra", std::vector<int32_t>{1, 2, 3});
    file.Commit();
  }
  const H5File file = H5File::OpenReadOnly(path);
  const Scene read = ReadSceneH5(file, "/checkpoint/scene");
  ExpectIdentical(scene, read);
  EXPECT_EQ(read.source, path + ":/checkpoint/scene");
  EXPECT_EQ(file.NumRows("/stats"), 1u);
  // The root of this file is not a scene.
  ExpectInputError([&] { ReadSceneH5(path); }, {path, "not a manisweep scene"});
  ExpectInputError([&] { ReadSceneH5(file, "/nowhere"); }, {path, "/nowhere", "not found"});
}

TEST_F(SceneH5Test, WrongOrMissingVersionIsRejected) {
  const std::string path = Path("version.h5");
  WriteSceneH5(RandomScene(2, 10, 2, 5), path);
  {
    H5File file = H5File::OpenReadWrite(path);
    file.SetIntAttribute("/", "format_version", 2);
  }
  ExpectInputError([&] { ReadSceneH5(path); },
                   {path, "scene format version 2 is not supported", "reads version 1"});
  {
    H5File file = H5File::OpenReadWrite(path);
    file.SetStringAttribute("/", "format_version", "1");
  }
  ExpectInputError([&] { ReadSceneH5(path); }, {path, "format_version", "expected an integer"});
  {
    H5File file = H5File::OpenReadWrite(path);
    file.SetIntAttribute("/", "format_version", 1);
    file.SetStringAttribute("/", "format", "something-else");
  }
  ExpectInputError([&] { ReadSceneH5(path); }, {path, "not a manisweep scene"});
  const std::string bare = Path("bare.h5");
  {
    H5File file = H5File::Create(bare);
    file.Write("/views/name", std::vector<std::string>{"a"});
    file.Commit();
  }
  ExpectInputError([&] { ReadSceneH5(bare); }, {bare, "no 'format_version' attribute"});
}

TEST_F(SceneH5Test, InconsistentContentNamesTheDataset) {
  const Scene scene = RandomScene(3, 20, 3, 6);
  const std::string path = Path("bad.h5");
  const auto damage = [&](const std::function<void(H5File&)>& edit) {
    WriteSceneH5(scene, path);
    H5File file = H5File::OpenReadWrite(path);
    edit(file);
    file.Close();
  };
  damage([](H5File& f) { f.Write("/views/fx", std::vector<double>{1, 2, 3, 4}); });
  ExpectInputError([&] { ReadSceneH5(path); },
                   {path, "/views/fx", "has shape (4,), expected (3,)"});

  damage([](H5File& f) { f.Write("/views/R", std::vector<double>(27, 0.0), {3, 9}); });
  ExpectInputError([&] { ReadSceneH5(path); }, {path, "/views/R"});

  damage([](H5File& f) { f.Write("/points/color", std::vector<float>(60, 0.0f), {20, 3}); });
  ExpectInputError([&] { ReadSceneH5(path); }, {path, "/points/color", "float32"});

  const size_t k = scene.NumObservations();
  damage([&](H5File& f) {
    std::vector<int64_t> offsets(21, 0);
    offsets[20] = static_cast<int64_t>(k);
    offsets[5] = static_cast<int64_t>(k) + 7;  // jumps past the end, then back
    f.Write("/observations/offsets", offsets);
  });
  ExpectInputError([&] { ReadSceneH5(path); }, {path, "/observations/offsets", "decreases"});

  damage([&](H5File& f) { f.Write("/observations/offsets", std::vector<int64_t>(21, 0)); });
  ExpectInputError([&] { ReadSceneH5(path); }, {path, "/observations/offsets", "ends at 0"});

  damage([&](H5File& f) { f.Write("/observations/view", std::vector<int32_t>(k, 99)); });
  ExpectInputError([&] { ReadSceneH5(path); }, {path, "refers to view 99"});

  damage([&](H5File& f) { f.Write("/views/width", std::vector<int32_t>{0, 10, 10}); });
  ExpectInputError([&] { ReadSceneH5(path); }, {path, "view 0", "image size"});

  damage([&](H5File& f) {
    f.Write("/views/t", std::vector<double>{0, 0, NAN, 0, 0, 0, 0, 0, 0}, {3, 3});
  });
  ExpectInputError([&] { ReadSceneH5(path); }, {path, "translation"});
}

TEST_F(SceneH5Test, TruncatedAndCorruptFilesNeverCrash) {
  const std::string good = Path("good.h5");
  WriteSceneH5(RandomScene(5, 300, 4, 7), good);
  const std::string bytes = ReadFileToString(good);
  const std::string path = Path("broken.h5");
  const auto write = [&](const std::string& data) {
    std::ofstream out(path, std::ios::binary | std::ios::trunc);
    out.write(data.data(), static_cast<std::streamsize>(data.size()));
  };
  for (size_t cut : {size_t{0}, size_t{100}, bytes.size() / 3, bytes.size() - 10}) {
    write(bytes.substr(0, cut));
    ExpectInputError([&] { ReadSceneH5(path); }, {path});
  }
  // Random single-byte damage anywhere: either a clean InputError naming the file, or (damage in
  // raw numbers) a scene that still validates. Nothing else.
  std::mt19937 rng(11);
  int errors = 0;
  for (int trial = 0; trial < 150; ++trial) {
    std::string corrupt = bytes;
    const size_t at = rng() % corrupt.size();
    corrupt[at] = static_cast<char>(corrupt[at] ^ (1 + rng() % 255));
    write(corrupt);
    try {
      ReadSceneH5(path).Validate();
    } catch (const InputError& e) {
      EXPECT_THAT(e.what(), HasSubstr(path)) << "byte " << at;
      ++errors;
    }
  }
  EXPECT_GT(errors, 0);
}

TEST_F(SceneH5Test, InvalidScenesAreNotWritten) {
  Scene scene = RandomScene(2, 5, 2, 8);
  scene.views[1].intrinsics.fx = -1;
  const std::string path = Path("invalid.h5");
  ExpectInputError([&] { WriteSceneH5(scene, path); }, {"random.nvm", "view 1", "focal length"});
  EXPECT_FALSE(fs::exists(path));
  EXPECT_FALSE(fs::exists(TempPathFor(path)));
}

TEST_F(SceneH5Test, SceneIoDispatchesH5) {
  const Scene scene = RandomScene(3, 40, 3, 9);
  const std::string path = Path("io.h5");
  WriteScene(scene, path, SceneFormat::kManisweepH5);
  EXPECT_EQ(DetectSceneFormat(path), SceneFormat::kManisweepH5);
  ExpectIdentical(scene, ReadScene(path));
  ExpectIdentical(scene, ReadScene(path, {}, SceneFormat::kManisweepH5));
  const std::string other = Path("auto.h5");
  WriteScene(scene, other, SceneFormat::kAuto);
  ExpectIdentical(scene, ReadScene(other));
}

}  // namespace
}  // namespace ms
