#include "scene/openmvg_io.h"

#include <spdlog/spdlog.h>

#include <cmath>
#include <filesystem>
#include <map>
#include <nlohmann/json.hpp>
#include <set>

#include "base/error.h"
#include "base/file_util.h"
#include "scene/format_util.h"

namespace fs = std::filesystem;

namespace ms {
namespace {

using json = nlohmann::json;

constexpr int64_t kMaxSide = int64_t{1} << 20;
using format::kMaxPixel;
// cereal's markers: the high bit flags the first occurrence of a polymorphic type or shared
// pointer (which then carries its name or data); this id marks a non-polymorphic object.
constexpr uint64_t kFirstOccurrence = 0x80000000u;
constexpr uint64_t kNotPolymorphic = 0x40000000u;

// One line, control characters escaped, bounded length: for nlohmann's messages, which quote
// the bytes they stopped at.
std::string OneLine(const std::string& text) {
  std::string out;
  for (char c : text.substr(0, 300)) {
    const unsigned char u = static_cast<unsigned char>(c);
    out += (u < 0x20 || u == 0x7f) ? '?' : c;
  }
  return out;
}

// nlohmann builds a DOM node per value; rejecting deep nesting first keeps memory and time
// proportional to sensible files (sfm_data nests 7 levels) and out of pathological ones.
void CheckNesting(const std::string& name, const std::string& text, int max_depth) {
  int depth = 0;
  bool in_string = false;
  for (size_t i = 0; i < text.size(); ++i) {
    const char c = text[i];
    if (in_string) {
      if (c == '\\') {
        ++i;
      } else if (c == '"') {
        in_string = false;
      }
    } else if (c == '"') {
      in_string = true;
    } else if (c == '[' || c == '{') {
      if (++depth > max_depth) {
        throw InputError(name + ": byte " + std::to_string(i) + ": JSON nested deeper than " +
                         std::to_string(max_depth) + " levels");
      }
    } else if (c == ']' || c == '}') {
      --depth;
    }
  }
}

class JsonReader {
 public:
  explicit JsonReader(std::string name) : name_(std::move(name)) {}

  [[noreturn]] void Fail(const std::string& path, const std::string& message) const {
    throw InputError(name_ + ": " + path + ": " + message);
  }
  const json& Field(const json& object, const char* key, const std::string& path) const {
    if (!object.is_object()) Fail(path, "expected an object");
    const auto it = object.find(key);
    if (it == object.end()) Fail(path, std::string("missing field '") + key + "'");
    return *it;
  }
  const json* OptionalField(const json& object, const char* key) const {
    const auto it = object.find(key);
    return it == object.end() ? nullptr : &*it;
  }
  const json& Array(const json& value, const std::string& path) const {
    if (!value.is_array()) Fail(path, "expected an array");
    return value;
  }
  double Number(const json& value, const std::string& path) const {
    if (!value.is_number()) Fail(path, "expected a number");
    const double d = value.get<double>();
    if (!std::isfinite(d)) Fail(path, "number is not finite");
    return d;
  }
  int64_t Integer(const json& value, const std::string& path, int64_t min, int64_t max) const {
    int64_t result = 0;
    if (value.is_number_unsigned()) {
      const uint64_t u = value.get<uint64_t>();
      if (u > static_cast<uint64_t>(max))
        Fail(path, "integer " + std::to_string(u) + " is too large");
      result = static_cast<int64_t>(u);
    } else if (value.is_number_integer()) {
      result = value.get<int64_t>();
    } else {
      Fail(path, "expected an integer");
    }
    if (result < min || result > max) {
      Fail(path, "integer " + std::to_string(result) + " is out of range [" + std::to_string(min) +
                     ", " + std::to_string(max) + "]");
    }
    return result;
  }
  std::string String(const json& value, const std::string& path) const {
    if (!value.is_string()) Fail(path, "expected a string");
    return value.get<std::string>();
  }
  std::vector<double> Numbers(const json& value, const std::string& path, size_t count) const {
    if (!value.is_array() || value.size() != count) {
      Fail(path, "expected an array of " + std::to_string(count) + " numbers");
    }
    std::vector<double> out;
    for (size_t i = 0; i < count; ++i)
      out.push_back(Number(value[i], path + "[" + std::to_string(i) + "]"));
    return out;
  }

  // The polymorphic type name of a cereal pointer ("" for a non-polymorphic object).
  std::string PolymorphicType(const json& value, const std::string& path) {
    const auto id = static_cast<uint64_t>(
        Integer(Field(value, "polymorphic_id", path), path + ".polymorphic_id", 0, UINT32_MAX));
    if (id == kNotPolymorphic) return "";
    if (id & kFirstOccurrence) {
      const std::string name =
          String(Field(value, "polymorphic_name", path), path + ".polymorphic_name");
      type_names_[id & ~kFirstOccurrence] = name;
      return name;
    }
    const auto it = type_names_.find(id);
    if (it == type_names_.end()) {
      Fail(path + ".polymorphic_id", "id " + std::to_string(id) + " names no earlier type");
    }
    return it->second;
  }
  // The data of a cereal shared pointer (first occurrence or a reference to an earlier one).
  const json& PointerData(const json& value, const std::string& path) {
    const json& wrapper = Field(value, "ptr_wrapper", path);
    const auto id = static_cast<uint64_t>(Integer(Field(wrapper, "id", path + ".ptr_wrapper"),
                                                  path + ".ptr_wrapper.id", 0, UINT32_MAX));
    if (id & kFirstOccurrence) {
      const json& data = Field(wrapper, "data", path + ".ptr_wrapper");
      shared_[id & ~kFirstOccurrence] = &data;
      return data;
    }
    const auto it = shared_.find(id);
    if (it == shared_.end()) {
      Fail(path + ".ptr_wrapper.id", "id " + std::to_string(id) + " refers to no earlier object");
    }
    return *it->second;
  }

 private:
  std::string name_;
  std::map<uint64_t, std::string> type_names_;
  std::map<uint64_t, const json*> shared_;
};

struct RawView {
  int64_t id = 0;
  std::string name;
  int64_t width = 0, height = 0;
  int64_t intrinsic = 0, pose = 0;
  std::string path;
};

struct RawIntrinsic {
  std::string type;
  int width = 0, height = 0;
  double focal = 0;
  std::vector<double> pp;
  std::vector<double> disto;
  std::string path;
};

using Poses = std::map<int64_t, std::pair<Eigen::Matrix3d, Eigen::Vector3d>>;

std::map<int64_t, RawView> ReadViews(const json& root, JsonReader& in) {
  std::map<int64_t, RawView> views;
  const json& views_json = in.Array(in.Field(root, "views", "(top level)"), "views");
  for (size_t i = 0; i < views_json.size(); ++i) {
    const std::string path = "views[" + std::to_string(i) + "]";
    const json& entry = views_json[i];
    RawView v;
    v.id = in.Integer(in.Field(entry, "key", path), path + ".key", 0, UINT32_MAX);
    const json& value = in.Field(entry, "value", path);
    in.PolymorphicType(value, path + ".value");
    const std::string data_path = path + ".value.ptr_wrapper.data";
    const json& data = in.PointerData(value, path + ".value");
    v.name = in.String(in.Field(data, "filename", data_path), data_path + ".filename");
    if (const json* local = in.OptionalField(data, "local_path")) {
      const std::string local_path = in.String(*local, data_path + ".local_path");
      if (!local_path.empty()) v.name = (fs::path(local_path) / v.name).generic_string();
    }
    v.width = in.Integer(in.Field(data, "width", data_path), data_path + ".width", 0, kMaxSide);
    v.height = in.Integer(in.Field(data, "height", data_path), data_path + ".height", 0, kMaxSide);
    v.intrinsic = in.Integer(in.Field(data, "id_intrinsic", data_path), data_path + ".id_intrinsic",
                             0, UINT32_MAX);
    v.pose =
        in.Integer(in.Field(data, "id_pose", data_path), data_path + ".id_pose", 0, UINT32_MAX);
    v.path = path;
    if (!views.emplace(v.id, v).second)
      in.Fail(path + ".key", "view id " + std::to_string(v.id) + " appears twice");
  }

  return views;
}

std::map<int64_t, RawIntrinsic> ReadIntrinsics(const json& root, JsonReader& in) {
  std::map<int64_t, RawIntrinsic> intrinsics;
  const json& intrinsics_json = in.Array(in.Field(root, "intrinsics", "(top level)"), "intrinsics");
  for (size_t i = 0; i < intrinsics_json.size(); ++i) {
    const std::string path = "intrinsics[" + std::to_string(i) + "]";
    const json& entry = intrinsics_json[i];
    const int64_t id = in.Integer(in.Field(entry, "key", path), path + ".key", 0, UINT32_MAX);
    const json& value = in.Field(entry, "value", path);
    RawIntrinsic k;
    k.type = in.PolymorphicType(value, path + ".value");
    const std::string data_path = path + ".value.ptr_wrapper.data";
    const json& data = in.PointerData(value, path + ".value");
    k.path = data_path;
    k.width = static_cast<int>(
        in.Integer(in.Field(data, "width", data_path), data_path + ".width", 0, kMaxSide));
    k.height = static_cast<int>(
        in.Integer(in.Field(data, "height", data_path), data_path + ".height", 0, kMaxSide));
    // Only pinhole types have these; others are rejected below if a posed view uses them.
    if (const json* f = in.OptionalField(data, "focal_length"))
      k.focal = in.Number(*f, data_path + ".focal_length");
    if (const json* pp = in.OptionalField(data, "principal_point"))
      k.pp = in.Numbers(*pp, data_path + ".principal_point", 2);
    static const std::pair<const char*, size_t> kDisto[] = {
        {"disto_k1", 1}, {"disto_k3", 3}, {"disto_t2", 5}};
    for (const auto& [field, count] : kDisto) {
      if (const json* d = in.OptionalField(data, field))
        k.disto = in.Numbers(*d, data_path + "." + field, count);
    }
    if (!intrinsics.emplace(id, k).second)
      in.Fail(path + ".key", "intrinsic id " + std::to_string(id) + " appears twice");
  }

  return intrinsics;
}

Poses ReadExtrinsics(const json& root, JsonReader& in) {
  Poses poses;
  const json& extrinsics_json = in.Array(in.Field(root, "extrinsics", "(top level)"), "extrinsics");
  for (size_t i = 0; i < extrinsics_json.size(); ++i) {
    const std::string path = "extrinsics[" + std::to_string(i) + "]";
    const json& entry = extrinsics_json[i];
    const int64_t id = in.Integer(in.Field(entry, "key", path), path + ".key", 0, UINT32_MAX);
    const json& value = in.Field(entry, "value", path);
    const json& rotation = in.Field(value, "rotation", path + ".value");
    if (!rotation.is_array() || rotation.size() != 3)
      in.Fail(path + ".value.rotation", "expected 3 rows");
    Eigen::Matrix3d R;
    for (int r = 0; r < 3; ++r) {
      const auto row =
          in.Numbers(rotation[r], path + ".value.rotation[" + std::to_string(r) + "]", 3);
      for (int c = 0; c < 3; ++c) R(r, c) = row[c];
    }
    const auto c =
        in.Numbers(in.Field(value, "center", path + ".value"), path + ".value.center", 3);
    if (!poses.emplace(id, std::make_pair(R, Eigen::Vector3d(c[0], c[1], c[2]))).second) {
      in.Fail(path + ".key", "pose id " + std::to_string(id) + " appears twice");
    }
  }

  return poses;
}

// A posed view's camera from its intrinsic (checked against the view) and pose.
View PosedView(const RawView& v, const RawIntrinsic& k,
               const std::pair<Eigen::Matrix3d, Eigen::Vector3d>& pose, JsonReader& in) {
  static const std::set<std::string> kSupported = {"pinhole", "pinhole_radial_k1",
                                                   "pinhole_radial_k3", "pinhole_brown_t2"};
  if (!kSupported.count(k.type)) {
    in.Fail(k.path, "camera type " + format::Quote(k.type) +
                        " is not supported (supported: pinhole, pinhole_radial_k1, "
                        "pinhole_radial_k3, pinhole_brown_t2)");
  }
  const size_t disto_count = k.type == "pinhole"             ? 0
                             : k.type == "pinhole_radial_k1" ? 1
                             : k.type == "pinhole_radial_k3" ? 3
                                                             : 5;
  if (k.pp.size() != 2 || k.disto.size() != disto_count) {
    in.Fail(k.path, "fields do not match camera type " + k.type);
  }
  if (v.width != k.width || v.height != k.height) {
    in.Fail(v.path, "view size " + std::to_string(v.width) + "x" + std::to_string(v.height) +
                        " differs from its intrinsic's " + std::to_string(k.width) + "x" +
                        std::to_string(k.height));
  }
  View view;
  view.name = v.name;
  Intrinsics& in_k = view.intrinsics;
  in_k.width = k.width;
  in_k.height = k.height;
  in_k.fx = in_k.fy = k.focal;
  in_k.cx = k.pp[0];
  in_k.cy = k.pp[1];
  if (disto_count >= 1) in_k.k1 = k.disto[0];
  if (disto_count >= 3) {
    in_k.k2 = k.disto[1];
    in_k.k3 = k.disto[2];
  }
  if (disto_count == 5) {
    in_k.p1 = k.disto[3];  // openMVG's t1 multiplies (r^2 + 2y^2) in y: OpenCV's p1
    in_k.p2 = k.disto[4];
  }
  view.R = format::NearestRotation(pose.first);
  view.t = -view.R * pose.second;
  return view;
}

// The views with a pose and an intrinsic become the scene's, in id order; `view_index` maps
// every openMVG view id to its scene view, -1 for those left out. Returns how many were.
size_t AddPosedViews(const std::map<int64_t, RawView>& views,
                     const std::map<int64_t, RawIntrinsic>& intrinsics, const Poses& poses,
                     JsonReader& in, Scene* scene, std::map<int64_t, int32_t>* view_index) {
  size_t unposed = 0;
  for (const auto& [id, v] : views) {
    const auto pose = poses.find(v.pose);
    const auto intrinsic = intrinsics.find(v.intrinsic);
    if (pose == poses.end() || intrinsic == intrinsics.end()) {
      (*view_index)[id] = -1;
      ++unposed;
      continue;
    }
    (*view_index)[id] = static_cast<int32_t>(scene->views.size());
    scene->views.push_back(PosedView(v, intrinsic->second, pose->second, in));
  }
  return unposed;
}

// The points and their observations in posed views; returns the observations dropped with
// the views left out.
size_t AddStructure(const json& root, const std::map<int64_t, int32_t>& view_index, JsonReader& in,
                    Scene* scene) {
  const json& structure = in.Array(in.Field(root, "structure", "(top level)"), "structure");
  scene->points.reserve(structure.size());
  size_t dropped = 0;
  for (size_t i = 0; i < structure.size(); ++i) {
    const std::string path = "structure[" + std::to_string(i) + "]";
    const json& value = in.Field(structure[i], "value", path);
    ScenePoint point;
    const auto X = in.Numbers(in.Field(value, "X", path + ".value"), path + ".value.X", 3);
    point.position = {X[0], X[1], X[2]};
    const json& observations =
        in.Array(in.Field(value, "observations", path + ".value"), path + ".value.observations");
    for (size_t o = 0; o < observations.size(); ++o) {
      const std::string obs_path = path + ".value.observations[" + std::to_string(o) + "]";
      const int64_t view_id =
          in.Integer(in.Field(observations[o], "key", obs_path), obs_path + ".key", 0, UINT32_MAX);
      const auto it = view_index.find(view_id);
      if (it == view_index.end())
        in.Fail(obs_path + ".key", "view " + std::to_string(view_id) + " is not in views");
      const auto x = in.Numbers(
          in.Field(in.Field(observations[o], "value", obs_path), "x", obs_path + ".value"),
          obs_path + ".value.x", 2);
      if (!(std::abs(x[0]) <= kMaxPixel && std::abs(x[1]) <= kMaxPixel)) {
        in.Fail(obs_path + ".value.x", "pixel coordinate out of range");
      }
      if (it->second < 0) {
        ++dropped;
        continue;
      }
      point.observations.push_back(
          {it->second, static_cast<float>(x[0]), static_cast<float>(x[1])});
    }
    scene->points.push_back(std::move(point));
  }
  return dropped;
}

}  // namespace

Scene ParseOpenMvg(const std::string& name, const std::string& contents, std::string* root_path) {
  CheckNesting(name, contents, 32);
  json root;
  try {
    root = json::parse(contents);
  } catch (const json::exception& e) {
    throw InputError(name + ": not valid JSON: " + OneLine(e.what()));
  }
  JsonReader in(name);
  if (!root.is_object()) in.Fail("(top level)", "expected an object");
  if (const json* rp = in.OptionalField(root, "root_path"); rp && root_path) {
    *root_path = in.String(*rp, "root_path");
  }
  const std::map<int64_t, RawView> views = ReadViews(root, in);
  const std::map<int64_t, RawIntrinsic> intrinsics = ReadIntrinsics(root, in);
  const Poses poses = ReadExtrinsics(root, in);
  Scene scene;
  scene.source = name;
  std::map<int64_t, int32_t> view_index;
  const size_t unposed = AddPosedViews(views, intrinsics, poses, in, &scene, &view_index);
  const size_t dropped = AddStructure(root, view_index, in, &scene);
  if (unposed > 0) {
    spdlog::info("{}: skipped {} views without pose or intrinsic, and {} observations in them",
                 name, unposed, dropped);
  }
  format::WarnDroppedDuplicates(name, format::SortAndDeduplicateObservations(&scene));
  return scene;
}

Scene ReadOpenMvg(const std::string& path, const SceneReadOptions& options) {
  std::string root_path;
  Scene scene = ParseOpenMvg(path, ReadFileToString(path), &root_path);
  std::vector<fs::path> extra;
  if (!root_path.empty()) extra.push_back(root_path);
  format::ImageLocator(path, options, extra).AttachImages(&scene);
  return scene;
}

namespace {

using ojson = nlohmann::ordered_json;

// root_path: the folder the image names are relative to, when all views agree on one; else "".
std::string CommonRootPath(const Scene& scene) {
  std::string root;
  for (const View& v : scene.views) {
    const std::string& image = v.image_path;
    const std::string suffix = "/" + v.name;
    if (image.size() <= suffix.size() ||
        image.compare(image.size() - suffix.size(), suffix.size(), suffix) != 0) {
      return "";
    }
    const std::string folder = image.substr(0, image.size() - suffix.size());
    if (root.empty()) root = folder;
    if (folder != root) return "";
  }
  return root;
}

// The distinct intrinsics, and each view's index into them.
std::vector<const Intrinsics*> DistinctIntrinsics(const Scene& scene,
                                                  std::vector<size_t>* intrinsic_of_view) {
  std::vector<const Intrinsics*> unique;
  for (const View& v : scene.views) {
    size_t found = unique.size();
    for (size_t c = 0; c < unique.size(); ++c) {
      if (*unique[c] == v.intrinsics) found = c;
    }
    if (found == unique.size()) unique.push_back(&v.intrinsics);
    intrinsic_of_view->push_back(found);
  }
  return unique;
}

ojson ViewsJson(const Scene& scene, const std::vector<size_t>& intrinsic_of_view,
                const std::string& path, uint64_t* next_pointer) {
  ojson views = ojson::array();
  for (size_t i = 0; i < scene.views.size(); ++i) {
    const View& v = scene.views[i];
    if (v.name.empty())
      throw InputError(path + ": view " + std::to_string(i) + ": empty image name");
    ojson data;
    data["local_path"] = "";
    data["filename"] = v.name;
    data["width"] = v.intrinsics.width;
    data["height"] = v.intrinsics.height;
    data["id_view"] = i;
    data["id_intrinsic"] = intrinsic_of_view[i];
    data["id_pose"] = i;
    ojson value;
    value["polymorphic_id"] = kNotPolymorphic;
    value["ptr_wrapper"] = {{"id", kFirstOccurrence | (*next_pointer)++}, {"data", data}};
    views.push_back({{"key", i}, {"value", value}});
  }
  return views;
}

// One intrinsic as openMVG's pinhole types (the plainest that holds its distortion).
ojson IntrinsicData(const Intrinsics& k, format::LossPolicy* loss, std::string* type) {
  if (k.fx != k.fy) loss->Report("fx != fy (openMVG has one focal length; written: their mean)");
  *type = "pinhole";
  const char* disto_name = nullptr;
  ojson disto = ojson::array();
  if (k.p1 != 0 || k.p2 != 0) {
    *type = "pinhole_brown_t2";
    disto_name = "disto_t2";
    disto = {k.k1, k.k2, k.k3, k.p1, k.p2};
  } else if (k.k2 != 0 || k.k3 != 0) {
    *type = "pinhole_radial_k3";
    disto_name = "disto_k3";
    disto = {k.k1, k.k2, k.k3};
  } else if (k.k1 != 0) {
    *type = "pinhole_radial_k1";
    disto_name = "disto_k1";
    disto = {k.k1};
  }
  ojson data;
  data["width"] = k.width;
  data["height"] = k.height;
  data["focal_length"] = 0.5 * (k.fx + k.fy);
  data["principal_point"] = {k.cx, k.cy};
  if (disto_name) data[disto_name] = disto;
  return data;
}

ojson IntrinsicsJson(const std::vector<const Intrinsics*>& unique, format::LossPolicy* loss,
                     uint64_t* next_pointer) {
  ojson intrinsics = ojson::array();
  std::map<std::string, uint64_t> type_ids;
  for (size_t c = 0; c < unique.size(); ++c) {
    std::string type;
    const ojson data = IntrinsicData(*unique[c], loss, &type);
    ojson value;
    const auto known = type_ids.find(type);
    if (known == type_ids.end()) {
      const uint64_t id = type_ids.size() + 1;
      type_ids[type] = id;
      value["polymorphic_id"] = kFirstOccurrence | id;
      value["polymorphic_name"] = type;
    } else {
      value["polymorphic_id"] = known->second;
    }
    value["ptr_wrapper"] = {{"id", kFirstOccurrence | (*next_pointer)++}, {"data", data}};
    intrinsics.push_back({{"key", c}, {"value", value}});
  }
  return intrinsics;
}

ojson ExtrinsicsJson(const Scene& scene) {
  ojson extrinsics = ojson::array();
  for (size_t i = 0; i < scene.views.size(); ++i) {
    const View& v = scene.views[i];
    ojson rotation = ojson::array();
    for (int r = 0; r < 3; ++r) rotation.push_back({v.R(r, 0), v.R(r, 1), v.R(r, 2)});
    const Eigen::Vector3d c = v.Center();
    extrinsics.push_back(
        {{"key", i}, {"value", {{"rotation", rotation}, {"center", {c.x(), c.y(), c.z()}}}}});
  }
  return extrinsics;
}

ojson StructureJson(const Scene& scene, format::LossPolicy* loss) {
  ojson structure = ojson::array();
  std::vector<int64_t> next_feature(scene.views.size(), 0);
  for (size_t p = 0; p < scene.points.size(); ++p) {
    const ScenePoint& point = scene.points[p];
    ojson observations = ojson::array();
    for (const Observation& o : point.observations) {
      double x = 0, y = 0;
      if (!format::ObservationPixel(scene, point, o, loss, &x, &y)) continue;
      observations.push_back(
          {{"key", o.view}, {"value", {{"id_feat", next_feature[o.view]++}, {"x", {x, y}}}}});
    }
    structure.push_back({{"key", p},
                         {"value",
                          {{"X", {point.position.x(), point.position.y(), point.position.z()}},
                           {"observations", observations}}}});
  }
  return structure;
}

}  // namespace

void WriteOpenMvg(const Scene& scene, const std::string& path, const SceneWriteOptions& options) {
  format::LossPolicy loss(path, "openMVG", options.allow_lossy);
  for (const ScenePoint& p : scene.points) {
    if (p.color != std::array<uint8_t, 3>{{128, 128, 128}}) {
      loss.Report("point colours (sfm_data has none)");
      break;
    }
  }
  std::vector<size_t> intrinsic_of_view;
  const std::vector<const Intrinsics*> unique = DistinctIntrinsics(scene, &intrinsic_of_view);
  uint64_t next_pointer = 1;
  ojson out;
  out["sfm_data_version"] = "0.3";
  out["root_path"] = CommonRootPath(scene);
  out["views"] = ViewsJson(scene, intrinsic_of_view, path, &next_pointer);
  out["intrinsics"] = IntrinsicsJson(unique, &loss, &next_pointer);
  out["extrinsics"] = ExtrinsicsJson(scene);
  out["structure"] = StructureJson(scene, &loss);
  out["control_points"] = ojson::array();
  const std::string text = out.dump(4);
  WriteFileAtomically(
      path,
      [&](std::ostream& s) {
        s.write(text.data(), text.size());
        s << "\n";
      },
      false);
}

}  // namespace ms
