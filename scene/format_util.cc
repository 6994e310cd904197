#include "scene/format_util.h"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <Eigen/Dense>
#include <algorithm>
#include <charconv>
#include <cmath>
#include <system_error>

#include "base/error.h"

namespace fs = std::filesystem;

namespace ms::format {

std::string Quote(std::string_view text) {
  constexpr size_t kMaxShown = 40;
  std::string out = "'";
  for (size_t i = 0; i < text.size() && i < kMaxShown; ++i) {
    const unsigned char c = static_cast<unsigned char>(text[i]);
    if (c < 0x20 || c >= 0x7f || c == '\'' || c == '\\') {
      out += fmt::format("\\x{:02x}", c);
    } else {
      out += static_cast<char>(c);
    }
  }
  out += "'";
  if (text.size() > kMaxShown)
    out += fmt::format(" (first {} of {} bytes)", kMaxShown, text.size());
  return out;
}

namespace {
std::string_view StripPlus(std::string_view token) {
  if (token.size() > 1 && token[0] == '+' && token[1] != '-' && token[1] != '+') {
    token.remove_prefix(1);
  }
  return token;
}
}  // namespace

double ParseDouble(const TextReader& reader, std::string_view token, const std::string& field) {
  const std::string_view text = StripPlus(token);
  double value = 0;
  const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), value);
  if (ec == std::errc::result_out_of_range) {
    reader.Fail(field + ": " + Quote(token) + " is out of the range of a double");
  }
  if (ec != std::errc() || end != text.data() + text.size() || text.empty()) {
    reader.Fail(field + ": " + Quote(token) + " is not a number");
  }
  if (!std::isfinite(value)) reader.Fail(field + ": value " + Quote(token) + " is not finite");
  return value;
}

int64_t ParseInt(const TextReader& reader, std::string_view token, const std::string& field,
                 int64_t min, int64_t max) {
  const std::string_view text = StripPlus(token);
  int64_t value = 0;
  const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), value);
  if (ec == std::errc::result_out_of_range) {
    reader.Fail(field + ": " + Quote(token) + " is out of range [" + std::to_string(min) + ", " +
                std::to_string(max) + "]");
  }
  if (ec != std::errc() || end != text.data() + text.size() || text.empty()) {
    reader.Fail(field + ": " + Quote(token) + " is not an integer");
  }
  if (value < min || value > max) {
    reader.Fail(field + ": " + std::to_string(value) + " is out of range [" + std::to_string(min) +
                ", " + std::to_string(max) + "]");
  }
  return value;
}

namespace {
bool IsBlank(char c) {
  return c == ' ' || c == '\t' || c == '\r' || c == '\n' || c == '\v' || c == '\f';
}
}  // namespace

bool FieldCursor::Next(std::string_view* field) {
  while (pos_ < line_.size() && IsBlank(line_[pos_])) ++pos_;
  if (pos_ >= line_.size()) return false;
  const size_t start = pos_;
  while (pos_ < line_.size() && !IsBlank(line_[pos_])) ++pos_;
  *field = line_.substr(start, pos_ - start);
  return true;
}

size_t CountFields(std::string_view line) {
  FieldCursor cursor(line);
  std::string_view field;
  size_t n = 0;
  while (cursor.Next(&field)) ++n;
  return n;
}

std::vector<std::string_view> SplitFieldsAtMost(const TextReader& reader, std::string_view line,
                                                size_t max_fields, const std::string& what) {
  const size_t n = CountFields(line);
  if (n > max_fields) {
    reader.Fail(what + ": " + std::to_string(n) + " fields, at most " + std::to_string(max_fields) +
                " expected");
  }
  return SplitFields(line);
}

std::string FormatDouble(double value) { return fmt::format("{}", value); }
std::string FormatFloat(float value) { return fmt::format("{}", value); }

size_t SortAndDeduplicateObservations(Scene* scene) {
  size_t before = scene->NumObservations();
  scene->NormalizeObservations();
  return before - scene->NumObservations();
}

void WarnDroppedDuplicates(const std::string& source, size_t dropped) {
  if (dropped > 0) {
    spdlog::warn("{}: {} observations repeat a view already in their point's track; kept the first",
                 source, dropped);
  }
}

size_t ReserveBound(uint64_t count, size_t file_bytes, size_t min_bytes_each) {
  const uint64_t bound =
      std::min<uint64_t>(file_bytes / std::max<size_t>(min_bytes_each, 1), 1 << 16);
  return static_cast<size_t>(std::min(count, bound));
}

// ---------------------------------------------------------------------------------------------

ImageLocator::ImageLocator(const fs::path& model_path, const SceneReadOptions& options,
                           std::vector<fs::path> extra_dirs)
    : model_name_(model_path.string()), options_(options) {
  std::error_code ec;
  fs::path folder = fs::absolute(model_path, ec).lexically_normal();
  if (folder.filename().empty()) folder = folder.parent_path();
  if (!fs::is_directory(folder, ec)) folder = folder.parent_path();
  for (int up = 0; up < 3 && !folder.empty(); ++up) {
    dirs_.push_back(folder);
    if (folder == folder.parent_path()) break;
    folder = folder.parent_path();
  }
  for (fs::path& dir : extra_dirs) dirs_.push_back(std::move(dir));
}

std::string ImageLocator::Find(const std::string& name) {
  if (name.empty()) return "";
  const auto cached = found_.find(name);
  if (cached != found_.end()) return cached->second;
  std::vector<fs::path> candidates;
  const fs::path relative(name);
  if (!options_.image_dir.empty()) {
    candidates.push_back(fs::path(options_.image_dir) / relative);
    candidates.push_back(fs::path(options_.image_dir) / relative.filename());
  }
  if (relative.is_absolute()) candidates.push_back(relative);
  for (const fs::path& dir : dirs_) {
    candidates.push_back(dir / relative);
    candidates.push_back(dir / "images" / relative);
  }
  std::string result;
  std::error_code ec;
  for (const fs::path& candidate : candidates) {
    if (fs::is_regular_file(candidate, ec)) {
      result = candidate.lexically_normal().string();
      break;
    }
  }
  found_[name] = result;
  return result;
}

ImageSize ImageLocator::RequireSize(const std::string& name, const std::string& why) {
  const auto cached = sizes_.find(name);
  if (cached != sizes_.end()) return cached->second;
  const std::string path = Find(name);
  if (path.empty()) {
    throw InputError(model_name_ + ": image " + Quote(name) + " not found (its size is needed " +
                     why + "); looked beside the model, in the two folders above it and their " +
                     "images/ folders; set the image folder with --image-dir");
  }
  const ImageSize size = ReadImageSize(path);
  sizes_[name] = size;
  return size;
}

void ImageLocator::AttachImages(Scene* scene) {
  for (size_t i = 0; i < scene->views.size(); ++i) {
    View& view = scene->views[i];
    view.image_path = Find(view.name);
    if (view.image_path.empty()) {
      if (options_.require_images) {
        throw InputError(model_name_ + ": view " + std::to_string(i) + ": image " +
                         Quote(view.name) + " not found (set the image folder with --image-dir)");
      }
      continue;
    }
    if (!options_.read_image_sizes) continue;
    auto cached = sizes_.find(view.name);
    const ImageSize size = cached != sizes_.end()
                               ? cached->second
                               : (sizes_[view.name] = ReadImageSize(view.image_path));
    if (size.width != view.intrinsics.width || size.height != view.intrinsics.height) {
      throw InputError(model_name_ + ": view " + std::to_string(i) + " (" + Quote(view.name) +
                       "): the model says " + std::to_string(view.intrinsics.width) + "x" +
                       std::to_string(view.intrinsics.height) + " but the image " +
                       view.image_path + " is " + std::to_string(size.width) + "x" +
                       std::to_string(size.height));
    }
  }
}

// ---------------------------------------------------------------------------------------------

void LossPolicy::Report(const std::string& what) {
  if (!allow_) {
    throw InputError(path_ + ": " + format_name_ + " cannot hold " + what +
                     " (pass --allow-lossy to write it anyway without that)");
  }
  if (reported_.insert(what).second) {
    spdlog::warn("{}: writing {} loses {}", path_, format_name_, what);
  }
}

void RequireTokenName(const std::string& path, const std::string& format_name, size_t view_index,
                      const std::string& name) {
  const bool bad = name.empty() || std::any_of(name.begin(), name.end(), [](char c) {
                     return c == ' ' || c == '\t' || c == '\n' || c == '\r' || c == '\v' ||
                            c == '\f' || c == '\0';
                   });
  if (bad) {
    throw InputError(path + ": view " + std::to_string(view_index) + ": image name " + Quote(name) +
                     " is empty or has white space, which " + format_name + " cannot store");
  }
}

bool ObservationPixel(const Scene& scene, const ScenePoint& point, const Observation& o,
                      LossPolicy* loss, double* x, double* y) {
  if (std::isfinite(o.x) && std::isfinite(o.y)) {
    *x = o.x;
    *y = o.y;
    return true;
  }
  loss->Report("observations without pixel coordinates (the projection of the point is written)");
  Eigen::Vector2d pixel;
  if (!scene.views[o.view].Project(point.position, &pixel)) return false;
  *x = static_cast<float>(pixel.x());
  *y = static_cast<float>(pixel.y());
  return true;
}

Eigen::Matrix3d NearestRotation(const Eigen::Matrix3d& R) {
  if (!R.allFinite()) return R;
  const double error = (R * R.transpose() - Eigen::Matrix3d::Identity()).norm();
  if (error < 1e-12 || error > 1e-3 || R.determinant() < 0) return R;
  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(R, Eigen::ComputeFullU | Eigen::ComputeFullV);
  return svd.matrixU() * svd.matrixV().transpose();
}

Intrinsics IntrinsicsFromK(const TextReader& reader, const Eigen::Matrix3d& K_in,
                           const std::string& what) {
  if (K_in(1, 0) != 0 || K_in(2, 0) != 0 || K_in(2, 1) != 0 || !(K_in(2, 2) > 0)) {
    reader.Fail(what + ": K must be upper triangular with a positive last entry");
  }
  const Eigen::Matrix3d K = K_in / K_in(2, 2);
  if (!(K(0, 0) > 0 && K(1, 1) > 0)) reader.Fail(what + ": focal lengths must be positive");
  if (std::abs(K(0, 1)) > 1e-9 * K(0, 0)) {
    reader.Fail(what + ": K has skew " + FormatDouble(K(0, 1)) + ", which is not supported");
  }
  Intrinsics k;
  k.fx = K(0, 0);
  k.fy = K(1, 1);
  k.cx = K(0, 2);
  k.cy = K(1, 2);
  return k;
}

double FitOpenCvToVisualSfm(double k, double max_radius, const std::string& where, double* k1,
                            double* k2, double* k3) {
  *k1 = *k2 = *k3 = 0;
  if (k == 0) return 0;
  if (!(max_radius > 0) || !std::isfinite(max_radius)) {
    throw InputError(where + ": cannot convert the radial distortion: image radius is not known");
  }
  // r_u = r_d (1 + k r_d^2) must grow with r_d over the image, or the model folds over.
  if (1 + 3 * k * max_radius * max_radius <= 0) {
    throw InputError(where + ": VisualSFM radial distortion " + FormatDouble(k) +
                     " folds the image over (1 + 3 k r^2 <= 0 inside the image)");
  }
  constexpr int kSamples = 256;
  Eigen::MatrixXd A(kSamples, 3);
  Eigen::VectorXd b(kSamples);
  for (int i = 0; i < kSamples; ++i) {
    const double rd = max_radius * (i + 1) / kSamples;
    const double ru = rd * (1 + k * rd * rd);
    const double ru2 = ru * ru;
    A(i, 0) = ru * ru2;
    A(i, 1) = A(i, 0) * ru2;
    A(i, 2) = A(i, 1) * ru2;
    b(i) = rd - ru;
  }
  const Eigen::Vector3d c = A.colPivHouseholderQr().solve(b);
  *k1 = c[0];
  *k2 = c[1];
  *k3 = c[2];
  double max_error = 0;
  for (int i = 0; i <= 4 * kSamples; ++i) {
    const double rd = max_radius * i / (4 * kSamples);
    const double ru = rd * (1 + k * rd * rd);
    const double ru2 = ru * ru;
    const double fitted = ru * (1 + ru2 * (c[0] + ru2 * (c[1] + ru2 * c[2])));
    max_error = std::max(max_error, std::abs(fitted - rd));
  }
  return max_error;
}

double FitVisualSfmToOpenCv(double k1, double k2, double k3, double max_radius) {
  if (k1 == 0 && k2 == 0 && k3 == 0) return 0;
  // Sample the forward model r_d(r_u), fit r_u - r_d = k r_d^3 in closed form.
  double numerator = 0, denominator = 0;
  constexpr int kSamples = 256;
  for (int i = 1; i <= kSamples; ++i) {
    const double ru = max_radius * i / kSamples;
    const double ru2 = ru * ru;
    const double rd = ru * (1 + ru2 * (k1 + ru2 * (k2 + ru2 * k3)));
    const double rd3 = rd * rd * rd;
    numerator += (ru - rd) * rd3;
    denominator += rd3 * rd3;
  }
  return denominator > 0 ? numerator / denominator : 0;
}

}  // namespace ms::format
