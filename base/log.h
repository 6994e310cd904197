// One logging library (spdlog), one format. Progress lines say what, how many, how long.
#pragma once

#include <spdlog/spdlog.h>

#include <chrono>
#include <cstdint>
#include <string>

namespace ms {

// Sets the global level from a name: trace, debug, info, warn, error, off.
// Throws InputError for an unknown name.
void SetLogLevel(const std::string& level_name);

// Installs the process-wide logger (stderr, "[time] [level] [tag] message"). The tag names the
// process role ("coordinator", "worker 3") so interleaved multi-process output stays readable.
void InitLogging(const std::string& process_tag = "manisweep");

// Monotonic stopwatch.
class Timer {
 public:
  Timer() : start_(std::chrono::steady_clock::now()) {}
  double Seconds() const {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  }
  void Restart() { start_ = std::chrono::steady_clock::now(); }

 private:
  std::chrono::steady_clock::time_point start_;
};

// Logs "<what>: done/total (pct) rate/s, elapsed" at most every `interval_s` seconds and once
// at Finish(). Cheap to call Update() in a hot loop.
class Progress {
 public:
  Progress(std::string what, int64_t total, double interval_s = 2.0);
  void Update(int64_t done) {
    if (done - last_checked_ >= check_stride_) MaybeLog(done);
  }
  // Logs the final line and returns the elapsed seconds.
  double Finish(int64_t done);

 private:
  void MaybeLog(int64_t done);
  std::string what_;
  int64_t total_;
  double interval_s_;
  double last_log_s_ = 0;
  int64_t last_checked_ = 0;
  int64_t check_stride_ = 1;
  Timer timer_;
};

}  // namespace ms
