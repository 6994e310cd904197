// GL tests: they run on whatever GlContext picks (llvmpipe in CI, a GPU where present).
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <opencv2/imgproc.hpp>

#include "base/error.h"
#include "gl/mesh_renderer.h"
#include "gl/objects.h"
#include "gl/projection.h"
#include "testing/gl_testing.h"

namespace ms::gl {
namespace {

class GlTest : public SharedGlContextTest {};

View TestView(int width = 64, int height = 48) {
  View view;
  view.name = "test";
  view.intrinsics.width = width;
  view.intrinsics.height = height;
  view.intrinsics.fx = 55;
  view.intrinsics.fy = 52;
  view.intrinsics.cx = 30.7;
  view.intrinsics.cy = 25.2;
  view.R = Eigen::AngleAxisd(0.3, Eigen::Vector3d(0.2, 1, 0.1).normalized()).toRotationMatrix();
  view.SetCenter(Eigen::Vector3d(0.5, -0.3, -4));
  return view;
}

// World point seen at image position (u, v) at camera depth z.
Eigen::Vector3d Unproject(const View& view, double u, double v, double z) {
  const Intrinsics& k = view.intrinsics;
  const Eigen::Vector3d cam((u - k.cx) / k.fx * z, (v - k.cy) / k.fy * z, z);
  return view.R.transpose() * (cam - view.t);
}

// A quad covering the whole image of `view` on the camera plane z = depth (+ tilt).
Mesh FacingQuad(const View& view, double depth, double tilt_x = 0, double tilt_y = 0) {
  const Intrinsics& k = view.intrinsics;
  Mesh mesh;
  const double margin = 5;
  for (auto [u, v] : {std::pair{-margin, -margin},
                      {k.width + margin, -margin},
                      {k.width + margin, k.height + margin},
                      {-margin, k.height + margin}}) {
    // Plane z = depth + tilt_x * x + tilt_y * y in camera coordinates, along the pixel ray.
    const double a = (u - k.cx) / k.fx, b = (v - k.cy) / k.fy;
    const double z = depth / (1 - tilt_x * a - tilt_y * b);
    mesh.vertices.push_back(Unproject(view, u, v, z));
  }
  // Counter-clockwise seen from the camera (x right, y up as the viewer sees it).
  mesh.faces = {{0, 3, 2}, {0, 2, 1}};
  return mesh;
}

TEST_F(GlTest, ContextReportsAModernCoreProfile) {
  const GlInfo& info = context_->info();
  EXPECT_FALSE(info.renderer.empty());
  EXPECT_FALSE(info.vendor.empty());
  EXPECT_TRUE(info.major > 4 || (info.major == 4 && info.minor >= 3)) << info.Summary();
  EXPECT_THAT(info.Summary(), ::testing::HasSubstr(info.renderer));
  EXPECT_TRUE(context_->IsCurrent());
  std::printf("OpenGL: %s\n", info.Summary().c_str());
}

TEST_F(GlTest, SecondContextCoexists) {
  {
    GlContext second;
    EXPECT_TRUE(second.IsCurrent());
    EXPECT_FALSE(context_->IsCurrent());
  }
  context_->MakeCurrent();
  EXPECT_TRUE(context_->IsCurrent());
  Buffer still_works(16);
  EXPECT_EQ(still_works.size(), 16u);
}

TEST(GlContextTest, MissingBackendGivesAClearError) {
  GlContextOptions options;
  options.backend = GlBackend::kDevice;
  options.device_index = 99;
  try {
    GlContext context(options);
    FAIL() << "got a context on EGL device 99";
  } catch (const InternalError& e) {
    EXPECT_THAT(e.what(), ::testing::HasSubstr("no usable OpenGL 4.3+ core context"));
    EXPECT_THAT(e.what(), ::testing::HasSubstr("device"));
  }
  EXPECT_THAT(DescribeGl(options), ::testing::StartsWith("unavailable: "));
}

TEST(GlContextOptions, RejectsOldVersionsAndUnknownBackends) {
  GlContextOptions options;
  options.min_minor = 2;
  EXPECT_THROW(options.Check(), InputError);
  EXPECT_THROW(ParseGlBackend("vulkan"), InputError);
  EXPECT_EQ(ParseGlBackend("surfaceless"), GlBackend::kSurfaceless);
}

TEST(Projection, MatchesViewProject) {
  const View view = TestView();
  for (DepthRange range : {DepthRange::kNegativeOneToOne, DepthRange::kReversedZeroToOne}) {
    const Eigen::Matrix4d p = GlProjection(view.intrinsics, 0.1, 100, range);
    for (const Eigen::Vector3d& x : {Eigen::Vector3d(0.1, 0.2, 0.3), Eigen::Vector3d(-1, 2, 5)}) {
      Eigen::Vector2d expected;
      ASSERT_TRUE(view.Project(x, &expected));
      const Eigen::Vector2d got = WindowFromCamera(p, view.intrinsics, view.ToCamera(x));
      EXPECT_NEAR((got - expected).norm(), 0, 1e-9);
    }
    // Depth maps to the ends of the range.
    const Eigen::Vector4d at_near = p * Eigen::Vector4d(0, 0, 0.1, 1);
    const Eigen::Vector4d at_far = p * Eigen::Vector4d(0, 0, 100, 1);
    const double near_ndc = at_near.z() / at_near.w(), far_ndc = at_far.z() / at_far.w();
    EXPECT_NEAR(near_ndc, range == DepthRange::kNegativeOneToOne ? -1 : 1, 1e-12);
    EXPECT_NEAR(far_ndc, range == DepthRange::kNegativeOneToOne ? 1 : 0, 1e-12);
  }
}

TEST_F(GlTest, PlaneAtKnownDepthRendersThatDepth) {
  const View view = TestView();
  MeshRenderer renderer(*context_, FacingQuad(view, 2.5));
  const DepthMaps maps = renderer.Render(view);
  ASSERT_EQ(maps.depth.type(), CV_32F);
  ASSERT_EQ(maps.depth.size(), cv::Size(64, 48));
  for (int r = 0; r < maps.depth.rows; ++r) {
    for (int c = 0; c < maps.depth.cols; ++c) {
      ASSERT_NEAR(maps.depth.at<float>(r, c), 2.5, 2.5e-4) << "pixel " << c << "," << r;
    }
  }
}

TEST_F(GlTest, TiltedPlaneDepthAndWorldPositionMatchThePinholeModel) {
  const View view = TestView(80, 60);
  const double tilt_x = 0.4, tilt_y = -0.25, depth = 3;
  MeshRenderer renderer(*context_, FacingQuad(view, depth, tilt_x, tilt_y));
  const DepthMaps maps = renderer.Render(view);
  const Intrinsics& k = view.intrinsics;
  double worst_depth = 0, worst_pixel = 0;
  for (int r = 0; r < maps.depth.rows; ++r) {
    for (int c = 0; c < maps.depth.cols; ++c) {
      const double a = (c + 0.5 - k.cx) / k.fx, b = (r + 0.5 - k.cy) / k.fy;
      const double expected = depth / (1 - tilt_x * a - tilt_y * b);
      const double got = maps.depth.at<float>(r, c);
      worst_depth = std::max(worst_depth, std::abs(got - expected) / expected);
      const cv::Vec3f w = maps.world.at<cv::Vec3f>(r, c);
      Eigen::Vector2d pixel;
      ASSERT_TRUE(view.Project(Eigen::Vector3d(w[0], w[1], w[2]), &pixel));
      worst_pixel = std::max(worst_pixel, (pixel - Eigen::Vector2d(c + 0.5, r + 0.5)).norm());
    }
  }
  EXPECT_LT(worst_depth, 1e-4);
  EXPECT_LT(worst_pixel, 2e-3);
}

TEST_F(GlTest, CoverageFollowsViewProjectAtPixelCentres) {
  // A triangle whose corners View::Project puts at known image positions (top-left origin):
  // exactly the pixels whose centres lie inside it must be covered (no flip, no half-pixel shift).
  const View view = TestView(64, 48);
  const Eigen::Vector2d a(10.3, 5.2), b(50.7, 9.9), c(14.1, 40.6);
  Mesh mesh;
  mesh.vertices = {Unproject(view, a.x(), a.y(), 3.0), Unproject(view, b.x(), b.y(), 3.4),
                   Unproject(view, c.x(), c.y(), 2.7)};
  mesh.faces = {{0, 1, 2}};
  for (int i = 0; i < 3; ++i) {
    Eigen::Vector2d p;
    ASSERT_TRUE(view.Project(mesh.vertices[i], &p));
    EXPECT_NEAR((p - (i == 0 ? a : i == 1 ? b : c)).norm(), 0, 1e-9);
  }
  MeshRenderer renderer(*context_, mesh);
  const DepthMaps maps = renderer.Render(view);
  auto cross = [](const Eigen::Vector2d& u, const Eigen::Vector2d& v) {
    return u.x() * v.y() - u.y() * v.x();
  };
  int covered = 0;
  for (int r = 0; r < 48; ++r) {
    for (int col = 0; col < 64; ++col) {
      const Eigen::Vector2d p(col + 0.5, r + 0.5);
      const double d0 = cross(b - a, p - a), d1 = cross(c - b, p - b), d2 = cross(a - c, p - c);
      const bool inside = (d0 > 0 && d1 > 0 && d2 > 0) || (d0 < 0 && d1 < 0 && d2 < 0);
      EXPECT_EQ(maps.depth.at<float>(r, col) > 0, inside) << "pixel " << col << "," << r;
      EXPECT_EQ(maps.face_id.at<int32_t>(r, col), inside ? 0 : -1);
      covered += inside;
    }
  }
  EXPECT_GT(covered, 300);
}

TEST(GlDepthRange, ConventionalDepthRangeRendersTheSameDepths) {
  // The path for drivers without glClipControl: GL's default [-1, 1] depth range.
  GlContextOptions options;
  options.use_clip_control = false;
  GlContext context(options);
  ASSERT_FALSE(context.info().clip_control);
  const View view = TestView(80, 60);
  Mesh mesh = FacingQuad(view, 3.0, 0.4, -0.25);
  const Mesh near = FacingQuad(view, 2.0);
  const int32_t base = static_cast<int32_t>(mesh.vertices.size());
  mesh.vertices.push_back(near.vertices[0]);  // a triangle of the nearer plane over part of it
  mesh.vertices.push_back(near.vertices[1]);
  mesh.vertices.push_back(near.vertices[3]);
  mesh.faces.push_back({base, base + 2, base + 1});
  MeshRenderer renderer(context, mesh);
  const DepthMaps maps = renderer.Render(view);
  const Intrinsics& k = view.intrinsics;
  int near_pixels = 0;
  for (int r = 0; r < maps.depth.rows; ++r) {
    for (int c = 0; c < maps.depth.cols; ++c) {
      const double a = (c + 0.5 - k.cx) / k.fx, b = (r + 0.5 - k.cy) / k.fy;
      const double plane = 3.0 / (1 - 0.4 * a + 0.25 * b);
      const double expected = maps.face_id.at<int32_t>(r, c) == 2 ? 2.0 : plane;
      near_pixels += maps.face_id.at<int32_t>(r, c) == 2;
      ASSERT_NEAR(maps.depth.at<float>(r, c), expected, 1e-4 * expected) << c << "," << r;
      ASSERT_LT(expected, plane + 1e-9) << "the nearer surface must win";
    }
  }
  EXPECT_GT(near_pixels, 1000);
}

TEST_F(GlTest, NearestSurfaceWinsAndFaceIdsNameIt) {
  const View view = TestView();
  Mesh mesh = FacingQuad(view, 4.0);
  const Mesh front = FacingQuad(view, 2.0);
  // Only the left half of the image gets the nearer quad (faces 2,3).
  const int base = static_cast<int>(mesh.vertices.size());
  const Intrinsics& k = view.intrinsics;
  mesh.vertices.push_back(Unproject(view, -5, -5, 2.0));
  mesh.vertices.push_back(Unproject(view, 32.25, -5, 2.0));
  mesh.vertices.push_back(Unproject(view, 32.25, k.height + 5, 2.0));
  mesh.vertices.push_back(Unproject(view, -5, k.height + 5, 2.0));
  mesh.faces.push_back({base, base + 3, base + 2});
  mesh.faces.push_back({base, base + 2, base + 1});
  MeshRenderer renderer(*context_, mesh);
  const DepthMaps maps = renderer.Render(view);
  for (int r = 0; r < k.height; ++r) {
    for (int c = 0; c < k.width; ++c) {
      const bool near_half = c + 0.5 < 32.25;
      ASSERT_NEAR(maps.depth.at<float>(r, c), near_half ? 2.0 : 4.0, 1e-3);
      const int face = maps.face_id.at<int32_t>(r, c);
      ASSERT_TRUE(near_half ? (face == 2 || face == 3) : (face == 0 || face == 1)) << face;
    }
  }
}

TEST_F(GlTest, BackFaceCullingKeepsFacesCounterClockwiseFromTheCamera) {
  const View view = TestView();
  Mesh front = FacingQuad(view, 2.0);
  Mesh back = front;
  for (auto& f : back.faces) std::swap(f[1], f[2]);
  DepthRenderOptions cull;
  cull.cull_back_faces = true;
  MeshRenderer front_renderer(*context_, front), back_renderer(*context_, back);
  EXPECT_EQ(front_renderer.Render(view, cull).CountValid(), 64 * 48);
  EXPECT_EQ(back_renderer.Render(view, cull).CountValid(), 0);
  EXPECT_EQ(back_renderer.Render(view).CountValid(), 64 * 48);  // no culling by default
}

TEST_F(GlTest, MeshBehindTheCameraRendersNothing) {
  View view = TestView();
  const Mesh mesh = FacingQuad(view, 2.0);
  view.R = Eigen::AngleAxisd(M_PI, Eigen::Vector3d::UnitY()).toRotationMatrix() * view.R;
  view.SetCenter(TestView().Center());
  MeshRenderer renderer(*context_, mesh);
  const DepthMaps maps = renderer.Render(view);
  EXPECT_EQ(maps.CountValid(), 0);
  EXPECT_EQ(maps.depth.size(), cv::Size(64, 48));
}

TEST_F(GlTest, BadMeshIndexIsAnInputError) {
  Mesh mesh;
  mesh.vertices = {Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitX(), Eigen::Vector3d::UnitY()};
  mesh.faces = {{0, 1, 3}};
  EXPECT_THROW(MeshRenderer(*context_, mesh), InputError);
}

TEST_F(GlTest, ShaderCompileErrorNamesTheShaderAndTheLine) {
  const std::string fragment =
      "#version 430 core\n"
      "out vec4 color;\n"
      "void main() {\n"
      "  color = vec4(undeclared_thing, 1.0);\n"
      "}\n";
  try {
    ShaderProgram("broken", {{ShaderStage::kFragment, "broken.frag", fragment, {}}});
    FAIL() << "compiled a broken shader";
  } catch (const InternalError& e) {
    const std::string message = e.what();
    EXPECT_THAT(message, ::testing::HasSubstr("broken.frag"));
    EXPECT_THAT(message, ::testing::HasSubstr("failed to compile"));
    EXPECT_THAT(message, ::testing::HasSubstr("undeclared_thing"));
    EXPECT_THAT(message, ::testing::HasSubstr("broken.frag:4:"));  // the source line, quoted
  }
}

TEST_F(GlTest, LinkErrorIsReported) {
  const std::string vertex =
      "#version 430 core\nout vec3 v_a;\nvoid main() { v_a = vec3(1); gl_Position = vec4(0); }\n";
  const std::string fragment =
      "#version 430 core\nin vec2 v_a;\nout vec4 c;\nvoid main() { c = vec4(v_a, 0, 1); }\n";
  EXPECT_THROW(ShaderProgram("mismatch", {{ShaderStage::kVertex, "m.vert", vertex, {}},
                                          {ShaderStage::kFragment, "m.frag", fragment, {}}}),
               InternalError);
}

TEST_F(GlTest, EmbeddedProgramsWithDefinesAndIncludesCompile) {
  EXPECT_NO_THROW(ShaderProgram::FromEmbedded({"surface.vert", "surface.frag"}, {"UNUSED 1"}));
  EXPECT_THROW(ShaderProgram::FromEmbedded({"nonexistent.frag"}), InternalError);
}

TEST_F(GlTest, ComputeShaderWritesStorageBuffer) {
  const std::string compute =
      "#version 430 core\n"
      "layout(local_size_x = 64) in;\n"
      "layout(std430, binding = 0) buffer Data { float values[]; };\n"
      "uniform float u_scale;\n"
      "uniform uint u_count;\n"
      "void main() {\n"
      "  uint i = gl_GlobalInvocationID.x;\n"
      "  if (i < u_count) values[i] = values[i] * u_scale + float(i);\n"
      "}\n";
  ShaderProgram program("scale", {{ShaderStage::kCompute, "scale.comp", compute, {}}});
  EXPECT_EQ(program.WorkGroupSize(), Eigen::Vector3i(64, 1, 1));
  std::vector<float> values(1000);
  for (size_t i = 0; i < values.size(); ++i) values[i] = 0.5f * i;
  Buffer buffer = Buffer::FromVector(values, BufferUsage::kDynamicCopy);
  buffer.BindStorage(0);
  program.Set("u_scale", 2.0f);
  program.Set("u_count", static_cast<uint32_t>(values.size()));
  program.Dispatch(16);
  MemoryBarrier();
  const std::vector<float> out = buffer.DownloadVector<float>(values.size());
  for (size_t i = 0; i < out.size(); ++i) ASSERT_FLOAT_EQ(out[i], 2 * i) << i;
  const std::vector<float> tail = buffer.DownloadVector<float>(2, 998);
  EXPECT_FLOAT_EQ(tail[1], 2 * 999);
}

TEST_F(GlTest, TexturesRoundTripAndFramebuffersReadSubRectangles) {
  cv::Mat values(13, 17, CV_32F);
  cv::randu(values, -5, 5);
  Texture2D texture(17, 13, TextureFormat::kR32F);
  texture.Upload(values);
  EXPECT_EQ(cv::norm(texture.Download(), values, cv::NORM_INF), 0);

  Framebuffer fb(40, 30, {TextureFormat::kR32F, TextureFormat::kRGBA32F, TextureFormat::kR32I},
                 /*with_depth=*/false);
  fb.Bind();
  fb.Clear(0, Eigen::Vector4f(1.5f, 0, 0, 0));
  fb.Clear(1, Eigen::Vector4f(1, 2, 3, 4));
  fb.ClearInt(2, Eigen::Vector4i(-7, 0, 0, 0));
  // The shader below writes attachment 0 only (the others become undefined): check them now.
  const cv::Rect rect(5, 9, 11, 7);
  const cv::Mat rgba = fb.Read(1, rect);
  ASSERT_EQ(rgba.type(), CV_32FC4);
  EXPECT_EQ(rgba.size(), rect.size());
  EXPECT_EQ(rgba.at<cv::Vec4f>(2, 3), cv::Vec4f(1, 2, 3, 4));
  const cv::Mat ints = fb.Read(2);
  ASSERT_EQ(ints.type(), CV_32S);
  EXPECT_EQ(ints.at<int32_t>(29, 39), -7);
  // Write a gradient through a fragment shader: value = x + 100 y at pixel centres.
  const std::string vertex =
      "#version 430 core\nvoid main() {\n"
      "  vec2 p = vec2(gl_VertexID == 1 ? 3.0 : -1.0, gl_VertexID == 2 ? 3.0 : -1.0);\n"
      "  gl_Position = vec4(p, 0.0, 1.0);\n}\n";
  const std::string fragment =
      "#version 430 core\nlayout(location = 0) out float o;\n"
      "void main() { o = gl_FragCoord.x + 100.0 * gl_FragCoord.y; }\n";
  ShaderProgram program("gradient", {{ShaderStage::kVertex, "g.vert", vertex, {}},
                                     {ShaderStage::kFragment, "g.frag", fragment, {}}});
  VertexArray empty;
  program.Use();
  empty.DrawTriangles(3);
  const cv::Mat all = fb.Read(0);
  EXPECT_FLOAT_EQ(all.at<float>(0, 0), 0.5f + 50.0f);  // row 0 = framebuffer row 0
  EXPECT_FLOAT_EQ(all.at<float>(7, 3), 3.5f + 750.0f);
  EXPECT_EQ(cv::norm(fb.Read(0, rect), all(rect), cv::NORM_INF), 0);
}

TEST_F(GlTest, SurfaceRendererDrawsDeterministicTexture) {
  const View view = TestView(96, 72);
  const Mesh mesh = FacingQuad(view, 3.0, 0.2, 0.1);
  SurfaceTexture texture;
  texture.materials[0].noise_period = 0.5f;
  SurfaceRenderer renderer(*context_, mesh, texture);
  SurfaceRenderOptions options;
  options.supersampling = 2;
  const cv::Mat a = renderer.Render(view, options);
  const cv::Mat b = renderer.Render(view, options);
  ASSERT_EQ(a.type(), CV_8UC3);
  ASSERT_EQ(a.size(), cv::Size(96, 72));
  EXPECT_EQ(cv::norm(a, b, cv::NORM_INF), 0);
  cv::Scalar mean, stddev;
  cv::meanStdDev(a, mean, stddev);
  EXPECT_GT(stddev[1], 8.0) << "the surface should be textured";
  // Another seed gives another pattern.
  texture.seed = 2;
  SurfaceRenderer other(*context_, mesh, texture);
  EXPECT_GT(cv::norm(other.Render(view, options), a, cv::NORM_L1) / a.total(), 3.0);
}

TEST_F(GlTest, SurfaceTextureIsChecked) {
  const View view = TestView();
  SurfaceTexture texture;
  texture.materials[0].photo = 0;  // no photos given
  EXPECT_THROW(SurfaceRenderer(*context_, FacingQuad(view, 2), texture), InputError);
}

}  // namespace
}  // namespace ms::gl
