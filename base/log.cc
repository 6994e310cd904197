#include "base/log.h"

#include <spdlog/sinks/stdout_color_sinks.h>

#include <algorithm>

#include "base/error.h"

namespace ms {

void SetLogLevel(const std::string& level_name) {
  const spdlog::level::level_enum level = spdlog::level::from_str(level_name);
  // from_str maps unknown names to "off"; only accept "off" when asked for.
  if (level == spdlog::level::off && level_name != "off") {
    throw InputError("--log-level: unknown level '" + level_name +
                     "' (use trace, debug, info, warn, error or off)");
  }
  spdlog::set_level(level);
}

void InitLogging(const std::string& process_tag) {
  auto logger = spdlog::stderr_color_mt("manisweep:" + process_tag);
  logger->set_pattern("[%H:%M:%S.%e] [%^%l%$] [" + process_tag + "] %v");
  spdlog::set_default_logger(logger);
  spdlog::flush_on(spdlog::level::warn);
}

Progress::Progress(std::string what, int64_t total, double interval_s)
    : what_(std::move(what)), total_(total), interval_s_(interval_s) {}

void Progress::MaybeLog(int64_t done) {
  last_checked_ = done;
  const double now = timer_.Seconds();
  // Adapt the stride so the clock is read roughly every 10 ms of work.
  if (now > 0 && done > 0) {
    const double per_item = now / static_cast<double>(done);
    check_stride_ = std::max<int64_t>(1, static_cast<int64_t>(0.01 / std::max(per_item, 1e-9)));
  }
  if (now - last_log_s_ < interval_s_) return;
  last_log_s_ = now;
  const double rate = now > 0 ? done / now : 0;
  if (total_ > 0) {
    spdlog::info("{}: {}/{} ({:.0f}%), {:.0f}/s, {:.1f} s", what_, done, total_,
                 100.0 * done / total_, rate, now);
  } else {
    spdlog::info("{}: {}, {:.0f}/s, {:.1f} s", what_, done, rate, now);
  }
}

double Progress::Finish(int64_t done) {
  const double elapsed = timer_.Seconds();
  spdlog::info("{}: {} done in {:.2f} s ({:.0f}/s)", what_, done, elapsed,
               elapsed > 0 ? done / elapsed : 0.0);
  return elapsed;
}

}  // namespace ms
