// The run report (`manisweep report RUN_DIR`, written by `reconstruct` at its end): one
// self-contained HTML page, report.html in the run folder, holding the run's input and options,
// per-iteration figures as charts, the initial, swept and refined meshes pictured from a few
// cameras beside the photographs, check-mesh and photo-consistency per mesh, and the accuracy
// table when the scene has a ground truth (docs/guides/report.md).
#pragma once

#include <string>

#include "gl/context.h"
#include "report/report_options.h"
#include "report/run_folder.h"

namespace ms {

// The page, measured now (pictures, check-mesh, photo-consistency, accuracy). A measurement
// that cannot be made (missing images, say) is reported on the page, not thrown.
std::string BuildRunReport(const gl::GlContext& gl, const RunFolder& run,
                           const ReportOptions& options);

// Reads `run_dir`, builds the page and writes it atomically to `output` (empty:
// RUN_DIR/report.html). Returns the path written. Throws InputError for a bad run folder.
std::string WriteRunReport(const std::string& run_dir, const ReportOptions& options,
                           const std::string& output = "");

// What a command that ends a run (reconstruct, coordinator) does about the report.
struct RunReportRequest {
  bool write = true;  // --report / --no-report
  ReportOptions options;
};

// RUN_DIR/report.html at the end of a run. The run's meshes are written by then, so a report
// that cannot be made is logged as a warning, not thrown.
void WriteRunReportAfterRun(const std::string& run_dir, const RunReportRequest& request);

}  // namespace ms
