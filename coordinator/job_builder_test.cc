// Jobs built as they are handed out: the same messages whatever the order or how often, and a
// camera that sees nothing is found out when its job is built.
#include "coordinator/job_builder.h"

#include <gtest/gtest.h>

#include "proto/wire.h"
#include "testing/scene_testing.h"
#include "testing/test_meshes.h"

namespace ms {
namespace {

using testing::TempDir;

// An octahedron of radius 0.3 around the origin, faces counter-clockwise seen from outside.
std::shared_ptr<const Mesh> Octahedron() {
  return std::make_shared<Mesh>(test_meshes::Octahedron(0.3));
}

struct Fixture {
  TempDir dir{"job_builder"};
  Scene scene;
  std::vector<std::vector<int>> neighbours;
  std::unique_ptr<ImageCatalog> images;

  Fixture() {
    scene = testing::MakeSyntheticScene(dir.path().string());
    View away = scene.views[0];  // camera 3 looks away from the octahedron
    away.R = -away.R;
    away.R.row(0) = -away.R.row(0);  // a rotation again (det +1)
    away.SetCenter(scene.views[0].Center());
    scene.views.push_back(away);
    scene.views.push_back(scene.views[2]);  // camera 4 has no neighbour
    neighbours = {{1, 2}, {0, 2}, {1, 0}, {0}, {}};
    images = std::make_unique<ImageCatalog>(ImageCatalog::WithoutImages(scene));
  }
  IterationJobSource Source() const {
    return IterationJobSource(scene, neighbours, Octahedron(), *images, 3, 77, JobBuildOptions());
  }
};

TEST(IterationJobSource, BuildsTheSameJobsInAnyOrderAndCountsEachOnce) {
  const Fixture f;
  IterationJobSource all = f.Source();
  ASSERT_EQ(all.job_ids(), (std::vector<uint64_t>{MakeJobId(3, 0), MakeJobId(3, 1), MakeJobId(3, 2),
                                                  MakeJobId(3, 3)}));
  const std::vector<wire::Job> whole = all.BuildAll();
  ASSERT_EQ(whole.size(), 3u) << "camera 3 sees no face, camera 4 has no neighbour";
  EXPECT_EQ(all.stats().jobs, 3);
  EXPECT_EQ(all.stats().skipped, (std::vector<std::string>{"camera 4: no neighbour",
                                                           "camera 3: sees no face of the mesh"}));

  // Built one or two at a time, backwards, and again (a requeued job): the same bytes.
  IterationJobSource lazy = f.Source();
  std::vector<std::optional<BuiltJob>> jobs = lazy.Build({MakeJobId(3, 3), MakeJobId(3, 2)});
  EXPECT_FALSE(jobs[0].has_value());
  ASSERT_TRUE(jobs[1].has_value());
  EXPECT_EQ(jobs[1]->job.SerializeAsString(), whole[2].SerializeAsString());
  for (int c : {1, 0, 1, 2}) {
    jobs = lazy.Build({MakeJobId(3, static_cast<uint32_t>(c))});
    ASSERT_TRUE(jobs[0].has_value());
    const BuiltJob& built = *jobs[0];
    EXPECT_EQ(built.job.SerializeAsString(), whole[c].SerializeAsString()) << "camera " << c;
    EXPECT_EQ(built.job.session_id(), 77u);
    EXPECT_EQ(built.job.iteration(), 3u);
    EXPECT_EQ(built.bytes, built.job.ByteSizeLong());
    // The bounds made from the visible mesh are those the coordinator used to unpack the job for.
    const JobBounds unpacked = JobBoundsFromWire(built.job);
    EXPECT_EQ(built.bounds.cameras, unpacked.cameras);
    EXPECT_EQ(built.bounds.min_depth, unpacked.min_depth);
    EXPECT_EQ(built.bounds.max_depth, unpacked.max_depth);
    EXPECT_GT(built.bounds.max_depth, built.bounds.min_depth);
  }
  const JobBuildStats a = all.stats(), b = lazy.stats();
  EXPECT_EQ(b.jobs, a.jobs);
  EXPECT_EQ(b.faces, a.faces);
  EXPECT_EQ(b.bytes, a.bytes);
  EXPECT_EQ(b.max_bytes, a.max_bytes);
  EXPECT_GT(b.faces, 0);
  EXPECT_EQ(b.skipped.size(), 2u);
}

TEST(IterationJobSource, AJobOverTheMessageLimitIsAnInputError) {
  const Fixture f;
  JobBuildOptions options;
  options.limits.max_message_bytes = 1100;  // the envelope's 1024 and a little
  IterationJobSource source(f.scene, f.neighbours, Octahedron(), *f.images, 1, 1, options);
  testing::ExpectInputError([&] { source.Build({MakeJobId(1, 0)}); },
                            {"camera 0", "--max-message-mb"});
}

}  // namespace
}  // namespace ms
