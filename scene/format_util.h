// Helpers shared by the scene importers/exporters (internal to ms_scene): token parsing with
// messages that stay one short line, exact number formatting, image lookup, and the policy for
// writes that would lose information.
#pragma once

#include <cstdint>
#include <filesystem>
#include <functional>
#include <map>
#include <set>
#include <string>
#include <string_view>
#include <vector>

#include "base/text_reader.h"
#include "scene/image_io.h"
#include "scene/scene.h"
#include "scene/scene_io.h"

namespace ms::format {

// Pixel coordinates beyond this are garbage (and overflow float): the importers reject them.
constexpr double kMaxPixel = 1e9;

// A token or name for an error message: at most 40 characters, non-printable bytes escaped, so
// the message stays one readable line whatever the input holds.
std::string Quote(std::string_view text);

// Parsing of one token with "<file>:<line>: <field>: <problem>" errors (through reader.Fail).
double ParseDouble(const TextReader& reader, std::string_view token, const std::string& field);
int64_t ParseInt(const TextReader& reader, std::string_view token, const std::string& field,
                 int64_t min, int64_t max);
inline double NextDouble(TextReader& reader, const std::string& field) {
  return ParseDouble(reader, reader.NextToken(field), field);
}
inline int64_t NextInt(TextReader& reader, const std::string& field, int64_t min, int64_t max) {
  return ParseInt(reader, reader.NextToken(field), field, min, max);
}

// The white-space separated fields of a line, one at a time: long lines (COLMAP's POINTS2D)
// are walked without building a vector of all their fields.
class FieldCursor {
 public:
  explicit FieldCursor(std::string_view line) : line_(line) {}
  bool Next(std::string_view* field);

 private:
  std::string_view line_;
  size_t pos_ = 0;
};
size_t CountFields(std::string_view line);
// SplitFields for lines that must have at most `max_fields` fields (fails through `reader`).
std::vector<std::string_view> SplitFieldsAtMost(const TextReader& reader, std::string_view line,
                                                size_t max_fields, const std::string& what);

// Shortest decimal text that reads back to exactly the same double (or float).
std::string FormatDouble(double value);
std::string FormatFloat(float value);

// Sorts every point's observations by view and drops repeated views (the first one in the
// source order is kept). Returns how many were dropped.
size_t SortAndDeduplicateObservations(Scene* scene);
// Logs a warning if `dropped` > 0.
void WarnDroppedDuplicates(const std::string& source, size_t dropped);

// How many items to reserve for a count read from a file: no file of `file_bytes` bytes holds
// more than file_bytes / min_bytes_each, and beyond 65536 the vector grows as items are parsed.
// Caps reservations only; never accepts a count.
size_t ReserveBound(uint64_t count, size_t file_bytes, size_t min_bytes_each);

// Finds the image files of a model and reads their sizes from headers (cached by name).
class ImageLocator {
 public:
  // `model_path` is the model file or directory; its folder, the folder above and the one above
  // that are searched (each directly and in an images/ subfolder), after options.image_dir.
  ImageLocator(const std::filesystem::path& model_path, const SceneReadOptions& options,
               std::vector<std::filesystem::path> extra_dirs = {});

  // Resolved path of an image name, or "" if none of the candidates exists.
  std::string Find(const std::string& name);
  // Size of the named image; throws InputError naming the model and the image when the image
  // cannot be found or read (`why` says what the size is needed for).
  ImageSize RequireSize(const std::string& name, const std::string& why);

  // Sets view.image_path for every view; with options.read_image_sizes checks found images'
  // sizes against the intrinsics; with options.require_images fails on a missing image.
  void AttachImages(Scene* scene);

  const std::string& model_name() const { return model_name_; }

 private:
  std::string model_name_;
  SceneReadOptions options_;
  std::vector<std::filesystem::path> dirs_;
  std::map<std::string, std::string> found_;
  std::map<std::string, ImageSize> sizes_;
};

// What a writer does when the target format cannot hold something of the scene: throw
// InputError (default) or, with allow_lossy, log each kind of loss once and go on.
class LossPolicy {
 public:
  LossPolicy(std::string path, std::string format_name, bool allow_lossy)
      : path_(std::move(path)), format_name_(std::move(format_name)), allow_(allow_lossy) {}
  void Report(const std::string& what);
  bool allowed() const { return allow_; }

 private:
  std::string path_;
  std::string format_name_;
  bool allow_;
  std::set<std::string> reported_;
};

// Throws InputError unless `name` is usable as one whitespace-free token in a text format.
void RequireTokenName(const std::string& path, const std::string& format_name, size_t view_index,
                      const std::string& name);

// Pixel coordinates of observation `o` of `point` for writing: the stored ones, or (with the
// loss reported) the projection of the point when the scene has no pixel coordinates.
bool ObservationPixel(const Scene& scene, const ScenePoint& point, const Observation& o,
                      LossPolicy* loss, double* x, double* y);

// Rotation matrices printed with few digits (Strecha's 6) are a little off orthonormal, which
// breaks R^T = R^-1 downstream: within 1e-3 of a rotation, the nearest rotation (SVD); exact
// rotations (error below 1e-12) and non-rotations (left for Scene::Validate to reject) unchanged.
Eigen::Matrix3d NearestRotation(const Eigen::Matrix3d& R);

// Pinhole intrinsics from a 3x3 K read at the reader's current line: K must be upper triangular
// with K(2,2) > 0 (it is divided out) and no skew beyond 1e-9 fx. Size and distortion stay 0.
Intrinsics IntrinsicsFromK(const TextReader& reader, const Eigen::Matrix3d& K,
                           const std::string& what);

// VisualSFM's radial model (NVM) maps a measured, distorted normalised point m to the undistorted
// one as m * (1 + k |m|^2). Least-squares fit of OpenCV's forward model (k1, k2, k3) to its
// inverse over radii up to `max_radius` (normalised, distorted). Returns the largest error in
// normalised units over the range; throws InputError (`where`) if the model folds over.
double FitOpenCvToVisualSfm(double k, double max_radius, const std::string& where, double* k1,
                            double* k2, double* k3);
// The converse: the VisualSFM k that best matches OpenCV radial (k1, k2, k3) over the range.
double FitVisualSfmToOpenCv(double k1, double k2, double k3, double max_radius);

}  // namespace ms::format
