// Strecha et al.'s ground-truth cameras (fountain-P11, Herz-Jesu, ...): a directory of
// "<image>.camera" files, cameras only. Each file holds, as whitespace-separated numbers:
//   K (3 rows), a distortion row (must be 0 0 0), R (3 rows, camera -> world), C (centre), W H
// so x ~ K R^T (X - C); we store R^T and t = -R^T C. Principal points are taken as written.
#pragma once

#include <string>

#include "scene/scene.h"
#include "scene/scene_io.h"

namespace ms {

// Parses one .camera file held in memory; the view is named after the file without ".camera".
View ParseStrechaCamera(const std::string& name, std::string contents);

// Reads every *.camera file of a directory, in name order.
Scene ReadStrecha(const std::string& dir, const SceneReadOptions& options);

// Writes "<image name>.camera" per view into `dir`. Lossy: distortion, all points.
void WriteStrecha(const Scene& scene, const std::string& dir, const SceneWriteOptions& options);

// True if `dir` is a directory holding at least one *.camera file.
bool IsStrechaDirectory(const std::string& dir);

}  // namespace ms
