#include "scene/scene_h5.h"

#include "base/error.h"
#include "scene/h5_file.h"

namespace ms {
namespace {

// Scene group layout (docs/reference/hdf5.md). Per-view values are one 1-D dataset per field so
// that h5py/h5dump users see names, not column indices.
constexpr const char* kViewDoubles[] = {"fx", "fy", "cx", "cy", "k1", "k2", "p1", "p2", "k3"};

double* ViewDouble(Intrinsics& k, int i) {
  double* fields[] = {&k.fx, &k.fy, &k.cx, &k.cy, &k.k1, &k.k2, &k.p1, &k.p2, &k.k3};
  return fields[i];
}

std::string Where(const H5File& file, const std::string& group) {
  return group == "/" || group.empty() ? file.path() : file.path() + ":" + group;
}

}  // namespace

void WriteSceneH5(const Scene& scene, H5File& file, const std::string& group) {
  scene.Validate();  // never write what the reader would refuse
  file.CreateGroup(group);
  const auto at = [&](const std::string& name) { return H5Join(group, name); };

  const size_t n = scene.views.size();
  std::vector<std::string> names(n), image_paths(n);
  std::vector<int32_t> widths(n), heights(n);
  std::vector<std::vector<double>> doubles(std::size(kViewDoubles), std::vector<double>(n));
  std::vector<double> rotations(9 * n), translations(3 * n);
  for (size_t i = 0; i < n; ++i) {
    const View& v = scene.views[i];
    names[i] = v.name;
    image_paths[i] = v.image_path;
    Intrinsics k = v.intrinsics;
    widths[i] = k.width;
    heights[i] = k.height;
    for (size_t f = 0; f < std::size(kViewDoubles); ++f) doubles[f][i] = *ViewDouble(k, f);
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 3; ++c) rotations[9 * i + 3 * r + c] = v.R(r, c);
      translations[3 * i + r] = v.t[r];
    }
  }
  file.Write(at("views/name"), names);
  file.Write(at("views/image_path"), image_paths);
  file.Write(at("views/width"), widths);
  file.Write(at("views/height"), heights);
  for (size_t f = 0; f < std::size(kViewDoubles); ++f) {
    file.Write(at(std::string("views/") + kViewDoubles[f]), doubles[f]);
  }
  file.Write(at("views/R"), rotations, {n, 3, 3});
  file.Write(at("views/t"), translations, {n, 3});

  // One array at a time, each freed before the next is built: the six together on top of the
  // scene would set the coordinator's peak of memory at its first checkpoint.
  const size_t m = scene.points.size();
  {
    std::vector<double> positions(3 * m);
    for (size_t i = 0; i < m; ++i) {
      for (int c = 0; c < 3; ++c) positions[3 * i + c] = scene.points[i].position[c];
    }
    file.Write(at("points/position"), positions, {m, 3});
  }
  {
    std::vector<uint8_t> colors(3 * m);
    for (size_t i = 0; i < m; ++i) {
      for (int c = 0; c < 3; ++c) colors[3 * i + c] = scene.points[i].color[c];
    }
    file.Write(at("points/color"), colors, {m, 3});
  }
  size_t k = 0;
  {
    std::vector<int64_t> offsets(m + 1, 0);
    for (size_t i = 0; i < m; ++i) {
      offsets[i + 1] = offsets[i] + static_cast<int64_t>(scene.points[i].observations.size());
    }
    k = static_cast<size_t>(offsets[m]);
    file.Write(at("observations/offsets"), offsets);
  }
  const auto write_observations = [&](const std::string& name, auto value_of) {
    std::vector<decltype(value_of(Observation{}))> values;
    values.reserve(k);
    for (const ScenePoint& p : scene.points) {
      for (const Observation& o : p.observations) values.push_back(value_of(o));
    }
    file.Write(at(name), values);
  };
  write_observations("observations/view", [](const Observation& o) { return int32_t{o.view}; });
  write_observations("observations/x", [](const Observation& o) { return float{o.x}; });
  write_observations("observations/y", [](const Observation& o) { return float{o.y}; });

  // The version goes last: a group whose writing was interrupted does not look like a scene.
  file.SetStringAttribute(group, "source", scene.source);
  file.SetStringAttribute(group, "format", kSceneH5FormatName);
  file.SetIntAttribute(group, "format_version", kSceneH5FormatVersion);
}

Scene ReadSceneH5(const H5File& file, const std::string& group) {
  const auto at = [&](const std::string& name) { return H5Join(group, name); };
  const auto fail = [&](const std::string& object, const std::string& what) {
    throw InputError(file.path() + ": " + object + ": " + what);
  };
  if (!file.IsGroup(group)) fail(group, "scene group not found");
  if (!file.HasAttribute(group, "format_version")) {
    fail(group, "not a manisweep scene (no 'format_version' attribute)");
  }
  const int64_t version = file.ReadIntAttribute(group, "format_version");
  if (version != kSceneH5FormatVersion) {
    fail(group, "scene format version " + std::to_string(version) +
                    " is not supported (this build reads version " +
                    std::to_string(kSceneH5FormatVersion) + ")");
  }
  if (!file.HasAttribute(group, "format") ||
      file.ReadStringAttribute(group, "format") != kSceneH5FormatName) {
    fail(group, std::string("not a manisweep scene ('format' attribute is not '") +
                    kSceneH5FormatName + "')");
  }

  Scene scene;
  scene.source = Where(file, group);

  const std::vector<std::string> names = file.Read<std::string>(at("views/name"), {kH5Any});
  const uint64_t n = names.size();
  const std::vector<std::string> image_paths = file.Read<std::string>(at("views/image_path"), {n});
  const std::vector<int32_t> widths = file.Read<int32_t>(at("views/width"), {n});
  const std::vector<int32_t> heights = file.Read<int32_t>(at("views/height"), {n});
  std::vector<std::vector<double>> doubles;
  for (const char* field : kViewDoubles) {
    doubles.push_back(file.Read<double>(at(std::string("views/") + field), {n}));
  }
  const std::vector<double> rotations = file.Read<double>(at("views/R"), {n, 3, 3});
  const std::vector<double> translations = file.Read<double>(at("views/t"), {n, 3});
  scene.views.resize(n);
  for (size_t i = 0; i < n; ++i) {
    View& v = scene.views[i];
    v.name = names[i];
    v.image_path = image_paths[i];
    v.intrinsics.width = widths[i];
    v.intrinsics.height = heights[i];
    for (size_t f = 0; f < std::size(kViewDoubles); ++f)
      *ViewDouble(v.intrinsics, f) = doubles[f][i];
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 3; ++c) v.R(r, c) = rotations[9 * i + 3 * r + c];
      v.t[r] = translations[3 * i + r];
    }
  }

  H5Shape shape;
  const std::vector<double> positions =
      file.Read<double>(at("points/position"), {kH5Any, 3}, &shape);
  const uint64_t m = shape[0];
  const std::vector<uint8_t> colors = file.Read<uint8_t>(at("points/color"), {m, 3});
  const std::vector<int64_t> offsets = file.Read<int64_t>(at("observations/offsets"), {m + 1});
  const std::vector<int32_t> obs_views = file.Read<int32_t>(at("observations/view"), {kH5Any});
  const uint64_t k = obs_views.size();
  const std::vector<float> xs = file.Read<float>(at("observations/x"), {k});
  const std::vector<float> ys = file.Read<float>(at("observations/y"), {k});
  // Offsets index the observation arrays: check them before using them.
  if (offsets[0] != 0) fail(at("observations/offsets"), "must start at 0");
  for (uint64_t i = 0; i < m; ++i) {
    if (offsets[i + 1] < offsets[i]) {
      fail(at("observations/offsets"), "decreases at point " + std::to_string(i));
    }
  }
  if (static_cast<uint64_t>(offsets[m]) != k) {
    fail(at("observations/offsets"), "ends at " + std::to_string(offsets[m]) + " but there are " +
                                         std::to_string(k) + " observations");
  }
  scene.points.resize(m);
  for (size_t i = 0; i < m; ++i) {
    ScenePoint& p = scene.points[i];
    for (int c = 0; c < 3; ++c) {
      p.position[c] = positions[3 * i + c];
      p.color[c] = colors[3 * i + c];
    }
    p.observations.reserve(offsets[i + 1] - offsets[i]);
    for (int64_t j = offsets[i]; j < offsets[i + 1]; ++j) {
      p.observations.push_back({obs_views[j], xs[j], ys[j]});
    }
  }
  scene.Validate();
  return scene;
}

std::string ReadSceneH5Source(const H5File& file, const std::string& group) {
  return file.ReadStringAttribute(group, "source");
}

Scene ReadSceneH5(const std::string& path) {
  const H5File file = H5File::OpenReadOnly(path);
  return ReadSceneH5(file, "/");
}

void WriteSceneH5(const Scene& scene, const std::string& path) {
  H5File file = H5File::Create(path);
  WriteSceneH5(scene, file, "/");
  file.Commit();
}

}  // namespace ms
