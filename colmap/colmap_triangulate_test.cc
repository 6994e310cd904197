// The colmap route's steps without colmap: database reading/writing on fake databases with
// colmap 3.8's schema, the mapping of database ids to views, the known-pose input model, the
// import of triangulated points, and the runner's failure path with a fake colmap script.
#include "colmap/colmap_triangulate.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <sqlite3.h>
#include <sys/stat.h>
#include <unistd.h>

#include <Eigen/Geometry>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <set>
#include <string>

#include "base/error.h"
#include "scene/colmap_io.h"
#include "testing/testing.h"

namespace fs = std::filesystem;

namespace ms {
namespace {

using ::testing::HasSubstr;

using testing::TempDir;

// colmap 3.8's tables (src/base/database.cc), as far as the route reads them.
constexpr const char* kSchema = R"sql(
CREATE TABLE cameras (camera_id INTEGER PRIMARY KEY AUTOINCREMENT NOT NULL,
  model INTEGER NOT NULL, width INTEGER NOT NULL, height INTEGER NOT NULL, params BLOB,
  prior_focal_length INTEGER NOT NULL);
CREATE TABLE images (image_id INTEGER PRIMARY KEY AUTOINCREMENT NOT NULL,
  name TEXT NOT NULL UNIQUE, camera_id INTEGER NOT NULL, prior_qw REAL, prior_qx REAL,
  prior_qy REAL, prior_qz REAL, prior_tx REAL, prior_ty REAL, prior_tz REAL);
CREATE TABLE keypoints (image_id INTEGER PRIMARY KEY NOT NULL, rows INTEGER NOT NULL,
  cols INTEGER NOT NULL, data BLOB);
CREATE TABLE two_view_geometries (pair_id INTEGER PRIMARY KEY NOT NULL, rows INTEGER NOT NULL,
  cols INTEGER NOT NULL, data BLOB, config INTEGER NOT NULL, F BLOB, E BLOB, H BLOB, qvec BLOB,
  tvec BLOB);
)sql";

void Sql(const std::string& path, const std::string& sql) {
  sqlite3* db = nullptr;
  ASSERT_EQ(sqlite3_open(path.c_str(), &db), SQLITE_OK);
  char* error = nullptr;
  const int rc = sqlite3_exec(db, sql.c_str(), nullptr, nullptr, &error);
  const std::string message = error ? error : "";
  sqlite3_free(error);
  sqlite3_close(db);
  ASSERT_EQ(rc, SQLITE_OK) << message;
}

// Inserts a camera with a SIMPLE_RADIAL placeholder (what colmap writes without camera_params).
std::string CameraRow(int id) {
  return "INSERT INTO cameras VALUES (" + std::to_string(id) + ", 2, 64, 48, X'" +
         std::string(64, '0') + "', 0);";
}

View MakeView(const std::string& name, double angle, double fx = 100) {
  View v;
  v.name = name;
  v.intrinsics.width = 64;
  v.intrinsics.height = 48;
  v.intrinsics.fx = fx;
  v.intrinsics.fy = fx * 1.01;
  v.intrinsics.cx = 31.7;
  v.intrinsics.cy = 24.2;
  v.R = Eigen::AngleAxisd(angle, Eigen::Vector3d(0.2, 1, 0.1).normalized()).toRotationMatrix();
  v.t = Eigen::Vector3d(0.1 * angle, -0.3, 2.0 + angle);
  return v;
}

Scene ThreeViews() {
  Scene scene;
  scene.source = "three";
  scene.views = {MakeView("a.png", 0.1), MakeView("sub/b.png", 0.5), MakeView("c.png", 0.9)};
  return scene;
}

// A database as colmap leaves it: ids in thread order, not in the views' order.
std::string FakeDatabase(const TempDir& dir) {
  const std::string path = dir / "database.db";
  Sql(path, kSchema);
  Sql(path, CameraRow(1) + CameraRow(2) + CameraRow(3) +
                "INSERT INTO images (image_id, name, camera_id) VALUES (1, 'c.png', 1), "
                "(2, 'a.png', 2), (3, 'sub/b.png', 3);"
                "INSERT INTO keypoints VALUES (1, 500, 6, NULL), (2, 700, 6, NULL), "
                "(3, 0, 6, NULL);"
                "INSERT INTO two_view_geometries (pair_id, rows, cols, config) VALUES "
                "(2147483649, 40, 2, 2), (2147483650, 0, 2, 1), (4294967299, 25, 2, 2);");
  return path;
}

TEST(ColmapDatabase, ReadsImagesCamerasAndVerifiedPairs) {
  TempDir dir;
  const ColmapDatabase db = ReadColmapDatabase(FakeDatabase(dir));
  ASSERT_EQ(db.images.size(), 3u);
  EXPECT_EQ(db.images[0].image_id, 1);
  EXPECT_EQ(db.images[0].name, "c.png");
  EXPECT_EQ(db.images[0].camera_id, 1);
  EXPECT_EQ(db.images[0].num_keypoints, 500);
  EXPECT_EQ(db.images[1].num_keypoints, 700);
  EXPECT_EQ(db.images[2].num_keypoints, 0);
  ASSERT_EQ(db.cameras.size(), 3u);
  EXPECT_EQ(db.cameras[0].model, 2);
  EXPECT_EQ(db.cameras[0].params.size(), 4u);
  EXPECT_FALSE(db.cameras[0].prior_focal_length);
  EXPECT_EQ(db.num_verified_pairs, 2);
  EXPECT_EQ(db.num_inlier_matches, 65);
}

TEST(ColmapDatabase, WritesKnownCameras) {
  TempDir dir;
  const std::string path = FakeDatabase(dir);
  ColmapDbCamera camera = ColmapCameraFor(MakeView("x", 0).intrinsics);
  camera.camera_id = 2;
  WriteColmapDatabaseCameras(path, {camera});
  const ColmapDatabase db = ReadColmapDatabase(path);
  EXPECT_EQ(db.cameras[1].model, 1);  // PINHOLE
  EXPECT_EQ(db.cameras[1].params, (std::vector<double>{100, 101, 31.7, 24.2}));
  EXPECT_TRUE(db.cameras[1].prior_focal_length);
  EXPECT_EQ(db.cameras[0].model, 2);  // others untouched

  camera.camera_id = 9;
  EXPECT_THAT([&] { WriteColmapDatabaseCameras(path, {camera}); },
              ::testing::ThrowsMessage<InputError>(HasSubstr("camera 9 is not in")));
}

TEST(ColmapDatabase, RejectsFilesThatAreNoColmapDatabase) {
  TempDir dir;
  EXPECT_THROW(ReadColmapDatabase(dir / "missing.db"), InputError);
  { std::ofstream(dir / "text.db") << "not sqlite at all, just some text that is long enough"; }
  EXPECT_THROW(ReadColmapDatabase(dir / "text.db"), InputError);
  Sql(dir / "other.db", "CREATE TABLE t (x INTEGER);");
  EXPECT_THAT([&] { ReadColmapDatabase(dir / "other.db"); },
              ::testing::ThrowsMessage<InputError>(HasSubstr("not a colmap database")));
}

TEST(ColmapCameraFor, PicksTheExactModel) {
  Intrinsics k = MakeView("x", 0).intrinsics;
  EXPECT_EQ(ColmapCameraFor(k).model, 1);
  k.k1 = 0.1;
  k.p2 = 0.01;
  const ColmapDbCamera opencv = ColmapCameraFor(k);
  EXPECT_EQ(opencv.model, 4);
  EXPECT_EQ(opencv.params, (std::vector<double>{100, 101, 31.7, 24.2, 0.1, 0, 0, 0.01}));
  k.k3 = 0.2;
  EXPECT_EQ(ColmapCameraFor(k).model, 6);
  EXPECT_EQ(ColmapCameraFor(k).params.size(), 12u);
}

TEST(ColmapWorkspaceNames, KeepsPlainNamesAndReplacesOthers) {
  Scene scene;
  for (const char* name : {"a.png", "dir/b.jpg", "with space.png", "../up.png", "/abs/c.png",
                           "dup.png", "dup.png", "ms_view_00002.png", ""}) {
    View v = MakeView(name, 0);
    v.image_path = std::string("/data/") + (*name ? name : "e.png");
    scene.views.push_back(v);
  }
  const std::vector<std::string> names = ColmapWorkspaceNames(scene);
  ASSERT_EQ(names.size(), scene.views.size());
  EXPECT_EQ(names[0], "a.png");
  EXPECT_EQ(names[1], "dir/b.jpg");
  EXPECT_EQ(names[3], "ms_view_00003.png");
  EXPECT_EQ(names[4], "ms_view_00004.png");
  EXPECT_EQ(names[5], "ms_view_00005.png");  // duplicates both get their own name
  EXPECT_EQ(names[6], "ms_view_00006.png");
  EXPECT_EQ(names[7], "ms_view_00002.png");  // a view's own name wins
  EXPECT_EQ(names[2], "ms_view_00002_1.png");
  EXPECT_EQ(names[8], "ms_view_00008.png");
  EXPECT_EQ(std::set<std::string>(names.begin(), names.end()).size(), names.size());
}

TEST(MatchDatabaseToViews, MapsIdsByName) {
  TempDir dir;
  const Scene scene = ThreeViews();
  const std::vector<std::string> names = ColmapWorkspaceNames(scene);
  const ColmapIdMap ids =
      MatchDatabaseToViews(scene, names, ReadColmapDatabase(FakeDatabase(dir)), "db");
  EXPECT_EQ(ids.image_id, (std::vector<int64_t>{2, 3, 1}));
  EXPECT_EQ(ids.camera_id, (std::vector<int64_t>{2, 3, 1}));
}

TEST(MatchDatabaseToViews, NamesTheImageColmapCouldNotRead) {
  Scene scene = ThreeViews();
  scene.views[1].image_path = "/data/sub/b.png";
  ColmapDatabase db;
  db.images = {{5, "a.png", 1, 10}, {6, "c.png", 2, 10}};
  EXPECT_THAT([&] { MatchDatabaseToViews(scene, ColmapWorkspaceNames(scene), db, "db"); },
              ::testing::ThrowsMessage<InputError>(HasSubstr("/data/sub/b.png: colmap did not")));
}

TEST(MatchDatabaseToViews, RejectsForeignImagesAndConflictingSharedCameras) {
  const Scene scene = ThreeViews();
  const auto names = ColmapWorkspaceNames(scene);
  ColmapDatabase db;
  db.images = {
      {1, "a.png", 1, 0}, {2, "sub/b.png", 2, 0}, {3, "c.png", 3, 0}, {4, "other.png", 4, 0}};
  EXPECT_THROW(MatchDatabaseToViews(scene, names, db, "db"), InternalError);
  db.images.pop_back();
  db.images[2].camera_id = 2;  // b and c share a camera, but their intrinsics are equal
  EXPECT_NO_THROW(MatchDatabaseToViews(scene, names, db, "db"));
  Scene different = scene;
  different.views[2].intrinsics.fx = 120;
  EXPECT_THROW(MatchDatabaseToViews(different, names, db, "db"), InternalError);
}

TEST(MakeKnownPoseModel, HoldsTheKnownCamerasUnderTheDatabaseIds) {
  Scene scene = ThreeViews();
  scene.views[2].intrinsics.k1 = -0.05;  // distortion goes to OPENCV
  const auto names = ColmapWorkspaceNames(scene);
  ColmapIdMap ids;
  ids.image_id = {7, 3, 5};
  ids.camera_id = {2, 9, 4};
  const ColmapFiles files = MakeKnownPoseModel(scene, names, ids);
  EXPECT_THAT(files.images, HasSubstr("\n7 "));
  EXPECT_THAT(files.images, HasSubstr(" 2 a.png\n\n"));
  EXPECT_THAT(files.images, HasSubstr(" 9 sub/b.png\n\n"));
  EXPECT_THAT(files.cameras, HasSubstr("\n4 OPENCV 64 48 "));
  EXPECT_THAT(files.cameras, HasSubstr("\n2 PINHOLE 64 48 100 101 31.699999999999999 "));
  EXPECT_EQ(files.points.find_first_not_of(" \n"), 0u);
  EXPECT_EQ(files.points[0], '#');

  // Read back with the project's COLMAP reader: views come in image-id order (3, 5, 7).
  const Scene back = ParseColmapModel(files, false);
  ASSERT_EQ(back.views.size(), 3u);
  EXPECT_TRUE(back.points.empty());
  const int order[] = {1, 2, 0};
  for (int j = 0; j < 3; ++j) {
    const View& v = scene.views[order[j]];
    const View& b = back.views[j];
    EXPECT_EQ(b.name, names[order[j]]);
    EXPECT_TRUE(b.intrinsics == v.intrinsics) << b.name;
    EXPECT_LT((b.R - v.R).norm(), 1e-14) << b.name;
    EXPECT_LT((b.t - v.t).norm(), 1e-15) << b.name;
  }
}

Scene FakeTriangulated(const Scene& scene, const std::vector<std::string>& names) {
  // colmap's model read back: views in image-id order (here c, a, b), named by workspace name.
  Scene t;
  t.source = "model_out";
  for (const int i : {2, 0, 1}) {
    View v = scene.views[i];
    v.name = names[i];
    v.image_path = "/workspace/images/" + names[i];
    t.views.push_back(v);
  }
  ScenePoint p;
  p.position = {0.1, 0.2, 3};
  p.color = {{10, 20, 30}};
  p.observations = {{0, 1.5f, 2.5f}, {2, 3.5f, 4.5f}};  // c and b
  t.points.push_back(p);
  p.observations = {{1, 5, 6}, {0, 7, 8}, {2, 9, 10}};  // a, c, b
  t.points.push_back(p);
  return t;
}

TEST(AttachTriangulatedPoints, RemapsObservationsAndKeepsTheInputViews) {
  Scene scene = ThreeViews();
  scene.views[0].image_path = "/data/a.png";
  const auto names = ColmapWorkspaceNames(scene);
  ColmapTriangulateResult result;
  const Scene out = AttachTriangulatedPoints(scene, names, FakeTriangulated(scene, names), &result);
  ASSERT_EQ(out.views.size(), 3u);
  EXPECT_EQ(out.views[0].image_path, "/data/a.png");
  EXPECT_EQ(out.views[1].name, "sub/b.png");
  ASSERT_EQ(out.points.size(), 2u);
  ASSERT_EQ(out.points[0].observations.size(), 2u);
  EXPECT_EQ(out.points[0].observations[0], (Observation{1, 3.5f, 4.5f}));
  EXPECT_EQ(out.points[0].observations[1], (Observation{2, 1.5f, 2.5f}));
  ASSERT_EQ(out.points[1].observations.size(), 3u);
  EXPECT_EQ(out.points[1].observations[0], (Observation{0, 5, 6}));
  EXPECT_EQ(out.points[1].observations[1], (Observation{1, 9, 10}));
  EXPECT_EQ(out.points[1].observations[2], (Observation{2, 7, 8}));
  EXPECT_EQ(out.points[1].color[2], 30);
  EXPECT_EQ(result.max_rotation_change, 0);
  EXPECT_EQ(result.max_translation_change, 0);
  EXPECT_NO_THROW(out.Validate());
}

TEST(AttachTriangulatedPoints, RejectsMovedPosesChangedIntrinsicsAndMissingViews) {
  const Scene scene = ThreeViews();
  const auto names = ColmapWorkspaceNames(scene);
  Scene moved = FakeTriangulated(scene, names);
  moved.views[1].t.x() += 1e-3;
  EXPECT_THAT([&] { AttachTriangulatedPoints(scene, names, moved, nullptr); },
              ::testing::ThrowsMessage<InternalError>(HasSubstr("moved a known pose")));
  Scene refocused = FakeTriangulated(scene, names);
  refocused.views[2].intrinsics.fx *= 1.001;
  EXPECT_THAT([&] { AttachTriangulatedPoints(scene, names, refocused, nullptr); },
              ::testing::ThrowsMessage<InternalError>(HasSubstr("intrinsics of view 'sub/b.png'")));
  Scene missing = FakeTriangulated(scene, names);
  missing.views.pop_back();
  missing.points.clear();
  EXPECT_THAT([&] { AttachTriangulatedPoints(scene, names, missing, nullptr); },
              ::testing::ThrowsMessage<InternalError>(HasSubstr("'sub/b.png' is missing")));
  // Noise at the level of a binary round trip passes.
  Scene noisy = FakeTriangulated(scene, names);
  noisy.views[0].t.z() += 1e-15;
  ColmapTriangulateResult result;
  EXPECT_NO_THROW(AttachTriangulatedPoints(scene, names, noisy, &result));
  EXPECT_GT(result.max_translation_change, 0);
}

TEST(ParseColmapVersion, ReadsTheHelpBanner) {
  EXPECT_EQ(ParseColmapVersion("COLMAP 3.8 -- Structure-from-Motion and Multi-View Stereo\n"),
            "COLMAP 3.8");
  EXPECT_EQ(ParseColmapVersion("\nCOLMAP 3.10.0 -- x"), "COLMAP 3.10.0");
  EXPECT_EQ(ParseColmapVersion("usage: something"), "");
  EXPECT_EQ(ParseColmapVersion("COLMAP -- x"), "");
}

TEST(ColmapImageError, FindsColmapsWordsAboutAnImage) {
  const std::string output =
      "Processed file [1/2]\n  Name:            b.png\n  ERROR: Failed to read image file "
      "format.\nProcessed file [2/2]\n  Name:            a.png\n  Dimensions:      640 x 480\n";
  EXPECT_EQ(ColmapImageError(output, "b.png"), "Failed to read image file format.");
  EXPECT_EQ(ColmapImageError(output, "a.png"), "");
  EXPECT_EQ(ColmapImageError(output, "c.png"), "");
  EXPECT_EQ(ColmapImageError("  Name: b.png", "b.png"), "");
}

TEST(ColmapTriangulateOptions, CheckNamesTheField) {
  ColmapTriangulateOptions options;
  EXPECT_NO_THROW(options.Check());
  options.matcher = "vocab_tree";
  EXPECT_THAT([&] { options.Check(); },
              ::testing::ThrowsMessage<InputError>(HasSubstr("matcher:")));
  options = {};
  options.threads = 0;
  EXPECT_THAT([&] { options.Check(); },
              ::testing::ThrowsMessage<InputError>(HasSubstr("threads:")));
  options = {};
  options.max_image_size = 8;
  EXPECT_THAT([&] { options.Check(); },
              ::testing::ThrowsMessage<InputError>(HasSubstr("max_image_size:")));
}

// A scene whose image files exist (contents do not matter before colmap runs).
Scene SceneWithImageFiles(const TempDir& dir) {
  Scene scene = ThreeViews();
  for (View& v : scene.views) {
    v.image_path = dir / fs::path(v.name).filename().string();
    std::ofstream(v.image_path) << "image";
  }
  return scene;
}

TEST(TriangulateWithColmap, BadInputFailsBeforeColmapRuns) {
  TempDir dir;
  Scene scene = SceneWithImageFiles(dir);
  ColmapTriangulateOptions options;
  options.colmap = dir / "no-such-colmap";
  EXPECT_THAT([&] { TriangulateWithColmap(scene, options); },
              ::testing::ThrowsMessage<InputError>(HasSubstr("Debian package `colmap`")));
  options.colmap = "no-such-colmap-in-path-xyz";
  EXPECT_THAT([&] { TriangulateWithColmap(scene, options); },
              ::testing::ThrowsMessage<InputError>(HasSubstr("is not in PATH")));

  Scene one = scene;
  one.views.resize(1);
  EXPECT_THAT([&] { TriangulateWithColmap(one, options); },
              ::testing::ThrowsMessage<InputError>(HasSubstr("at least two views")));
  scene.views[2].image_path = dir / "gone.png";
  EXPECT_THAT([&] { TriangulateWithColmap(scene, options); },
              ::testing::ThrowsMessage<InputError>(HasSubstr("gone.png not found")));
}

// A stand-in for colmap: answers -h like 3.8, creates the database like feature_extractor, then
// fails the way colmap 3.8 does on a failed CHECK (glog fatal line, stack frames, SIGABRT).
void WriteFakeColmap(const std::string& path) {
  std::ofstream(path) << R"sh(#!/bin/sh
case "$1" in
  -h) echo "COLMAP 3.8 -- Structure-from-Motion and Multi-View Stereo"; exit 0 ;;
  feature_extractor)
    echo "Processed file [1/3]"
    echo "F20260101 00:00:00.000000 1 feature_extraction.cc:99] Check failed: fake failure"
    echo "*** Check failure stack trace: ***"
    echo "    @     0x7f0000000000  google::LogMessage::Fail()"
    kill -ABRT $$ ;;
esac
exit 3
)sh";
  ::chmod(path.c_str(), 0755);
}

TEST(TriangulateWithColmap, ColmapFailureIsAnInternalErrorWithItsLogLine) {
  TempDir dir;
  const Scene scene = SceneWithImageFiles(dir);
  ColmapTriangulateOptions options;
  options.colmap = dir / "colmap";
  WriteFakeColmap(options.colmap);
  options.workspace = dir / "ws";
  EXPECT_THAT([&] { TriangulateWithColmap(scene, options); },
              ::testing::ThrowsMessage<InternalError>(::testing::AllOf(
                  HasSubstr("colmap feature_extractor was killed by signal 6"),
                  HasSubstr("Check failed: fake failure"), HasSubstr("ws/colmap.log"))));
  // A workspace the user named stays, with the log and the image links.
  EXPECT_TRUE(fs::is_regular_file(dir / "ws/colmap.log"));
  EXPECT_TRUE(fs::is_symlink(dir / "ws/images/sub/b.png"));
  std::ifstream list(dir / "ws/image_list.txt");
  std::string contents((std::istreambuf_iterator<char>(list)), std::istreambuf_iterator<char>());
  EXPECT_EQ(contents, "a.png\nsub/b.png\nc.png\n");

  // A temporary workspace is removed after the failure; the message says how to keep it.
  options.workspace.clear();
  const std::string tmp = dir / "tmp";
  fs::create_directories(tmp);
  const char* old_tmpdir = std::getenv("TMPDIR");
  const std::string saved = old_tmpdir ? old_tmpdir : "";
  ::setenv("TMPDIR", tmp.c_str(), 1);
  EXPECT_THAT([&] { TriangulateWithColmap(scene, options); },
              ::testing::ThrowsMessage<InternalError>(HasSubstr("--keep-workspace")));
  if (old_tmpdir) {
    ::setenv("TMPDIR", saved.c_str(), 1);
  } else {
    ::unsetenv("TMPDIR");
  }
  EXPECT_TRUE(fs::is_empty(tmp));
}

}  // namespace
}  // namespace ms
