#include "colmap/colmap_triangulate.h"

#include <fcntl.h>
#include <fmt/format.h>
#include <spdlog/spdlog.h>
#include <sqlite3.h>
#include <sys/prctl.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>  // fork, execve, environ (glibc with _GNU_SOURCE)

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdlib>
#include <cstring>
#include <deque>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <memory>
#include <set>
#include <sstream>
#include <thread>
#include <unordered_map>

#include "base/error.h"
#include "base/file_util.h"
#include "base/log.h"
#include "base/subprocess.h"

namespace fs = std::filesystem;

namespace ms {
namespace {

// COLMAP's camera model ids and names (src/base/camera_models.h) for the models we write.
constexpr int kPinhole = 1;
constexpr int kOpenCv = 4;
constexpr int kFullOpenCv = 6;

const char* ModelName(int model) {
  switch (model) {
    case kPinhole:
      return "PINHOLE";
    case kOpenCv:
      return "OPENCV";
    case kFullOpenCv:
      return "FULL_OPENCV";
  }
  return "UNKNOWN";
}

// Exact text for a double: 17 significant digits read back to the same value.
std::string Exact(double value) { return fmt::format("{:.17g}", value); }

std::string JoinParams(const std::vector<double>& params, const char* separator) {
  std::string out;
  for (size_t i = 0; i < params.size(); ++i) {
    if (i > 0) out += separator;
    out += Exact(params[i]);
  }
  return out;
}

// ---- sqlite ---------------------------------------------------------------------------------

struct SqliteCloser {
  void operator()(sqlite3* db) const { sqlite3_close(db); }
};
struct StatementCloser {
  void operator()(sqlite3_stmt* s) const { sqlite3_finalize(s); }
};
using SqliteDb = std::unique_ptr<sqlite3, SqliteCloser>;
using Statement = std::unique_ptr<sqlite3_stmt, StatementCloser>;

SqliteDb OpenDatabase(const std::string& path, bool writable) {
  std::error_code ec;
  if (!fs::is_regular_file(path, ec)) throw InputError(path + ": colmap database not found");
  sqlite3* raw = nullptr;
  const int flags = writable ? SQLITE_OPEN_READWRITE : SQLITE_OPEN_READONLY;
  const int rc = sqlite3_open_v2(path.c_str(), &raw, flags, nullptr);
  SqliteDb db(raw);
  if (rc != SQLITE_OK) {
    throw InputError(path + ": cannot open as an SQLite database: " +
                     (raw ? sqlite3_errmsg(raw) : sqlite3_errstr(rc)));
  }
  sqlite3_busy_timeout(raw, 5000);
  return db;
}

Statement Prepare(sqlite3* db, const std::string& path, const char* sql) {
  sqlite3_stmt* raw = nullptr;
  if (sqlite3_prepare_v2(db, sql, -1, &raw, nullptr) != SQLITE_OK) {
    throw InputError(path + ": not a colmap database (" + sqlite3_errmsg(db) + " in \"" + sql +
                     "\")");
  }
  return Statement(raw);
}

// Steps a statement; true while rows come. Throws InputError on an error.
bool Step(sqlite3* db, sqlite3_stmt* statement, const std::string& path) {
  const int rc = sqlite3_step(statement);
  if (rc == SQLITE_ROW) return true;
  if (rc == SQLITE_DONE) return false;
  throw InputError(path + ": database query failed: " + sqlite3_errmsg(db));
}

std::string ColumnText(sqlite3_stmt* s, int column) {
  const unsigned char* text = sqlite3_column_text(s, column);
  const int bytes = sqlite3_column_bytes(s, column);
  return text ? std::string(reinterpret_cast<const char*>(text), static_cast<size_t>(bytes))
              : std::string();
}

void Execute(sqlite3* db, const std::string& path, const char* sql) {
  char* message = nullptr;
  if (sqlite3_exec(db, sql, nullptr, nullptr, &message) != SQLITE_OK) {
    const std::string text = message ? message : "unknown error";
    sqlite3_free(message);
    throw InputError(path + ": database statement \"" + sql + "\" failed: " + text);
  }
}

// ---- running colmap -------------------------------------------------------------------------

// Resolves the executable: a path with a '/' as given, a bare name through PATH.
std::string FindExecutable(const std::string& name) {
  std::error_code ec;
  const auto executable = [&](const fs::path& p) {
    return fs::is_regular_file(p, ec) && ::access(p.c_str(), X_OK) == 0;
  };
  if (name.find('/') != std::string::npos) return executable(name) ? name : "";
  const char* path_env = std::getenv("PATH");
  std::string path = path_env ? path_env : "/usr/local/bin:/usr/bin:/bin";
  size_t start = 0;
  while (start <= path.size()) {
    const size_t end = std::min(path.find(':', start), path.size());
    const std::string dir = path.substr(start, end - start);
    const fs::path candidate = fs::path(dir.empty() ? "." : dir) / name;
    if (executable(candidate)) return candidate.string();
    start = end + 1;
  }
  return "";
}

// The last meaningful lines of colmap's output (no stack frames, no blank lines).
std::vector<std::string> TailLines(const std::string& text, size_t count) {
  std::deque<std::string> lines;
  size_t start = 0;
  while (start < text.size()) {
    size_t end = text.find('\n', start);
    if (end == std::string::npos) end = text.size();
    std::string line = text.substr(start, end - start);
    start = end + 1;
    while (!line.empty() && (line.back() == '\r' || line.back() == ' ')) line.pop_back();
    const size_t first = line.find_first_not_of(' ');
    if (first == std::string::npos) continue;
    if (line.compare(first, 1, "@") == 0) continue;  // glog stack frame "    @ 0x..."
    if (line.find_first_not_of("=-") == std::string::npos) continue;  // banner rules
    lines.push_back(std::move(line));
    if (lines.size() > count) lines.pop_front();
  }
  return {lines.begin(), lines.end()};
}

// Feeds the lines a stage prints to a parser that logs progress, and logs a heartbeat when the
// stage has been silent for a while (exhaustive matching of a few images is one long block).
class StageMonitor {
 public:
  using LineParser = std::function<void(const std::string& line, StageMonitor& monitor)>;
  StageMonitor(std::string stage, LineParser parser)
      : stage_(std::move(stage)), parser_(std::move(parser)) {}

  void Feed(const std::string& text) {
    pending_ += text;
    size_t newline;
    while ((newline = pending_.find('\n')) != std::string::npos) {
      std::string line = pending_.substr(0, newline);
      pending_.erase(0, newline + 1);
      if (parser_) parser_(line, *this);
    }
  }
  // Progress of `done` out of `total` items of `what` (e.g. "images"), logged at most every 5 s.
  void Report(int64_t done, int64_t total, const std::string& what) {
    const double now = timer_.Seconds();
    if (now - last_report_s_ < 5.0) return;
    spdlog::info(
        "colmap {}: {}/{} {} ({:.0f}%), {:.0f} s", stage_, done, total, what,
        100.0 * static_cast<double>(done) / static_cast<double>(std::max<int64_t>(1, total)), now);
    last_report_s_ = now;
  }
  // A new phase of the stage; worth an info line only once the stage takes a while.
  void Phase(const std::string& phase) {
    if (phase == phase_) return;
    phase_ = phase;
    const double now = timer_.Seconds();
    if (now >= 5.0) {
      spdlog::info("colmap {}: {}, {:.0f} s", stage_, phase, now);
    } else {
      spdlog::debug("colmap {}: {}, {:.1f} s", stage_, phase, now);
    }
    last_report_s_ = now;
  }
  void Heartbeat() {
    const double now = timer_.Seconds();
    if (now - last_report_s_ >= 30.0) {
      spdlog::info("colmap {}: running, {:.0f} s", stage_, now);
      last_report_s_ = now;
    }
  }

 private:
  std::string stage_;
  LineParser parser_;
  std::string pending_;
  std::string phase_;
  Timer timer_;
  double last_report_s_ = 0;
};

// SIGINT/SIGTERM while colmap runs: stop it, let the stack unwind (the temporary workspace is
// removed) and report the interruption, instead of dying with colmap's files left in /tmp.
volatile std::sig_atomic_t g_interrupt_signal = 0;
extern "C" void OnInterrupt(int signal_number) { g_interrupt_signal = signal_number; }

class InterruptScope {
 public:
  InterruptScope() {
    g_interrupt_signal = 0;
    struct sigaction action {};
    action.sa_handler = OnInterrupt;
    sigemptyset(&action.sa_mask);
    sigaction(SIGINT, &action, &old_int_);
    sigaction(SIGTERM, &action, &old_term_);
  }
  ~InterruptScope() {
    sigaction(SIGINT, &old_int_, nullptr);
    sigaction(SIGTERM, &old_term_, nullptr);
  }
  InterruptScope(const InterruptScope&) = delete;
  InterruptScope& operator=(const InterruptScope&) = delete;

 private:
  struct sigaction old_int_ {};
  struct sigaction old_term_ {};
};

// Parses "[a/b" at the start of `text` (after `prefix`); false if it is not there.
bool ParseFraction(const std::string& line, const std::string& prefix, int64_t* a, int64_t* b) {
  const size_t at = line.find(prefix);
  if (at == std::string::npos) return false;
  long long x = 0, y = 0;
  if (std::sscanf(line.c_str() + at + prefix.size(), "%lld/%lld", &x, &y) != 2) return false;
  *a = x;
  *b = y;
  return y > 0;
}

// CPU time (clock ticks, every thread) a process has used so far; -1 if it cannot be read.
int64_t CpuTicks(pid_t pid) {
  std::ifstream in("/proc/" + std::to_string(pid) + "/stat");
  const std::string stat((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const size_t name_end = stat.rfind(')');
  if (name_end == std::string::npos) return -1;
  std::istringstream fields(stat.substr(name_end + 1));
  std::string field;
  int64_t ticks = 0;
  for (int i = 3; i <= 15 && fields >> field; ++i) {
    if (i >= 14) ticks += std::atoll(field.c_str());  // utime, stime
  }
  return ticks;
}

// colmap can deadlock (seen once in feature_extractor on a truncated PNG: every thread waiting
// on a futex). A stage that uses no CPU and writes nothing this long is killed and run once more.
constexpr double kStallSeconds = 120;

class ColmapRunner {
 public:
  ColmapRunner(std::string executable, fs::path log_path, bool log_kept)
      : executable_(std::move(executable)),
        stdbuf_(FindExecutable("stdbuf")),
        log_path_(std::move(log_path)),
        log_kept_(log_kept) {}

  // Runs `colmap <stage> <args>` with its stdout and stderr appended to the log; returns what
  // it wrote. Throws InternalError (with the log's tail logged) unless it exits with status 0.
  std::string Run(const std::string& stage, const std::vector<std::string>& args,
                  const StageMonitor::LineParser& parser = nullptr) {
    std::string command = executable_ + " " + stage;
    for (const std::string& a : args) command += " " + a;
    {
      std::ofstream log(log_path_, std::ios::app);
      log << "\n#### manisweep runs: " << command << "\n";
      if (!log) throw InputError(log_path_.string() + ": cannot write the colmap log");
    }
    spdlog::debug("running {}", command);
    std::error_code ec;
    const uint64_t start_offset = fs::file_size(log_path_, ec);

    const SubprocessOptions child = ChildOptions(stage, args);
    const auto launch = [&] { return StartSubprocess(child); };
    pid_t pid = launch();

    InterruptScope interrupt_scope;
    StageMonitor monitor(stage, parser);
    uint64_t offset = start_offset;
    std::string output;
    const auto drain = [&] {
      std::ifstream in(log_path_, std::ios::binary);
      in.seekg(static_cast<std::streamoff>(offset));
      std::string chunk((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
      offset += chunk.size();
      monitor.Feed(chunk);
      output += chunk;
    };
    int status = 0;
    int64_t last_ticks = CpuTicks(pid);
    uint64_t last_offset = offset;
    Timer idle;
    bool retried = false;
    while (true) {
      const pid_t done = ::waitpid(pid, &status, WNOHANG);
      if (done == pid) break;
      const int64_t ticks = CpuTicks(pid);
      if (ticks != last_ticks || offset != last_offset) {
        last_ticks = ticks;
        last_offset = offset;
        idle.Restart();
      } else if (idle.Seconds() > kStallSeconds) {
        ::kill(pid, SIGKILL);
        ::waitpid(pid, &status, 0);
        if (retried) {
          throw InternalError(fmt::format(
              "colmap {} made no progress (no CPU time, no output) for {:.0f} s, twice; killed "
              "(log: {})",
              stage, kStallSeconds, log_path_.string()));
        }
        spdlog::warn(
            "colmap {} made no progress for {:.0f} s (deadlocked?): killed, running it "
            "once more",
            stage, kStallSeconds);
        retried = true;
        output.clear();
        pid = launch();
        last_ticks = CpuTicks(pid);
        idle.Restart();
        continue;
      }
      if (done < 0 && errno != EINTR) {
        throw InternalError(std::string("waiting for colmap: ") + strerror(errno));
      }
      if (g_interrupt_signal != 0) {
        ::kill(pid, SIGTERM);
        ::waitpid(pid, &status, 0);
        throw InternalError(fmt::format("colmap {}: interrupted by signal {} ({})", stage,
                                        static_cast<int>(g_interrupt_signal),
                                        strsignal(g_interrupt_signal)));
      }
      drain();
      monitor.Heartbeat();
      std::this_thread::sleep_for(std::chrono::milliseconds(200));
    }
    drain();
    if (WIFEXITED(status) && WEXITSTATUS(status) == 0) return output;

    ThrowFailure(stage, status, output);
  }

 private:
  // How `colmap <stage> <args>` is started: line-buffered, appending to the log, no display.
  SubprocessOptions ChildOptions(const std::string& stage,
                                 const std::vector<std::string>& args) const {
    SubprocessOptions child;
    // colmap prints progress through std::cout, which is block-buffered into a file; coreutils'
    // stdbuf makes it line-buffered so progress shows while a stage runs.
    if (!stdbuf_.empty()) child.argv = {stdbuf_, "-oL", "-eL"};
    child.argv.push_back(executable_);
    child.argv.push_back(stage);
    child.argv.insert(child.argv.end(), args.begin(), args.end());
    child.executable = child.argv[0];
    // SIFT on the CPU needs no display; should any Qt code start anyway, it must not look for
    // X. glog's own log files go to the workspace instead of /tmp.
    bool has_qt_platform = false;
    for (char** e = environ; e && *e; ++e) {
      const std::string entry = *e;
      if (entry.rfind("GLOG_log_dir=", 0) == 0) continue;
      if (entry.rfind("QT_QPA_PLATFORM=", 0) == 0) has_qt_platform = true;
      child.env.push_back(entry);
    }
    if (!has_qt_platform) child.env.push_back("QT_QPA_PLATFORM=offscreen");
    child.env.push_back("GLOG_log_dir=" + log_path_.parent_path().string());
    child.output_path = log_path_.string();
    child.stdin_from_null = true;  // colmap dies with us (e.g. when a timeout kills manisweep)
    return child;
  }

  // The one error line for a stage that ended with `status`, after logging its output's tail.
  [[noreturn]] void ThrowFailure(const std::string& stage, int status,
                                 const std::string& output) const {
    const std::string how = WIFSIGNALED(status)
                                ? fmt::format("was killed by signal {} ({})", WTERMSIG(status),
                                              strsignal(WTERMSIG(status)))
                                : fmt::format("exited with status {}", WEXITSTATUS(status));
    const std::vector<std::string> tail = TailLines(output, 20);
    spdlog::error("colmap {} {}; the last lines of its output ({}):", stage, how,
                  log_path_.string());
    for (const std::string& line : tail) spdlog::error("  | {}", line);
    // The one line: glog's fatal message ("F... file.cc:123] Check failed: ...") if there is
    // one, else colmap's last line.
    std::string reason;
    for (const std::string& line : tail) {
      if ((line.size() > 1 && line[0] == 'F' &&
           std::isdigit(static_cast<unsigned char>(line[1]))) ||
          line.find("ERROR") != std::string::npos ||
          line.find("Check failed") != std::string::npos) {
        reason = line;
      }
    }
    if (reason.empty() && !tail.empty()) reason = tail.back();
    if (reason.size() > 200) reason = reason.substr(0, 200) + "...";
    throw InternalError(fmt::format("colmap {} {}{}{} (log: {}{})", stage, how,
                                    reason.empty() ? "" : ": ", reason, log_path_.string(),
                                    log_kept_ ? "" : "; removed, rerun with --keep-workspace"));
  }

  std::string executable_;
  std::string stdbuf_;  // empty if coreutils' stdbuf is missing
  fs::path log_path_;
  bool log_kept_;
};

// Removes the temporary workspace when the run ends, however it ends.
class WorkspaceGuard {
 public:
  WorkspaceGuard(fs::path path, bool remove) : path_(std::move(path)), remove_(remove) {}
  ~WorkspaceGuard() {
    if (!remove_) return;
    std::error_code ec;
    fs::remove_all(path_, ec);
    if (ec)
      spdlog::warn("{}: cannot remove the colmap workspace: {}", path_.string(), ec.message());
  }
  WorkspaceGuard(const WorkspaceGuard&) = delete;
  WorkspaceGuard& operator=(const WorkspaceGuard&) = delete;

 private:
  fs::path path_;
  bool remove_;
};

bool SafeRelativeName(const std::string& name) {
  if (name.empty() || name.size() > 1000 || name.front() == '/') return false;
  for (const char c : name) {
    const auto u = static_cast<unsigned char>(c);
    if (u <= 0x20 || u == 0x7f || c == '\\') return false;
  }
  for (const auto& part : fs::path(name)) {
    if (part == ".." || part == "." || part.empty()) return false;
  }
  return name.back() != '/';
}

double RelativeDifference(double a, double b) {
  return std::abs(a - b) / std::max(1.0, std::max(std::abs(a), std::abs(b)));
}

double IntrinsicsChange(const Intrinsics& a, const Intrinsics& b) {
  if (a.width != b.width || a.height != b.height) return 1.0;
  double change = 0;
  for (const auto& [x, y] : {std::pair{a.fx, b.fx}, std::pair{a.fy, b.fy}, std::pair{a.cx, b.cx},
                             std::pair{a.cy, b.cy}, std::pair{a.k1, b.k1}, std::pair{a.k2, b.k2},
                             std::pair{a.p1, b.p1}, std::pair{a.p2, b.p2}, std::pair{a.k3, b.k3}}) {
    change = std::max(change, RelativeDifference(x, y));
  }
  return change;
}

}  // namespace

void ColmapTriangulateOptions::Check() const {
  if (colmap.empty()) throw InputError("colmap: the executable must not be empty");
  if (matcher != "exhaustive" && matcher != "sequential") {
    throw InputError("matcher: must be exhaustive or sequential, got '" + matcher + "'");
  }
  if (max_image_size < 16 || max_image_size > 100000) {
    throw InputError("max_image_size: must be in [16, 100000], got " +
                     std::to_string(max_image_size));
  }
  if (threads == 0 || threads < -1 || threads > 4096) {
    throw InputError("threads: must be -1 (all cores) or in [1, 4096], got " +
                     std::to_string(threads));
  }
}

// ---- database -------------------------------------------------------------------------------

ColmapDatabase ReadColmapDatabase(const std::string& path) {
  SqliteDb db = OpenDatabase(path, false);
  ColmapDatabase out;
  std::unordered_map<int64_t, size_t> image_index;
  {
    Statement s = Prepare(db.get(), path, "SELECT image_id, name, camera_id FROM images");
    while (Step(db.get(), s.get(), path)) {
      ColmapDbImage image;
      image.image_id = sqlite3_column_int64(s.get(), 0);
      image.name = ColumnText(s.get(), 1);
      image.camera_id = sqlite3_column_int64(s.get(), 2);
      image_index[image.image_id] = out.images.size();
      out.images.push_back(std::move(image));
    }
  }
  {
    Statement s = Prepare(db.get(), path, "SELECT image_id, rows FROM keypoints");
    while (Step(db.get(), s.get(), path)) {
      const auto it = image_index.find(sqlite3_column_int64(s.get(), 0));
      if (it != image_index.end())
        out.images[it->second].num_keypoints = sqlite3_column_int64(s.get(), 1);
    }
  }
  {
    Statement s = Prepare(db.get(), path,
                          "SELECT camera_id, model, width, height, params, prior_focal_length "
                          "FROM cameras");
    while (Step(db.get(), s.get(), path)) {
      ColmapDbCamera camera;
      camera.camera_id = sqlite3_column_int64(s.get(), 0);
      camera.model = sqlite3_column_int(s.get(), 1);
      camera.width = sqlite3_column_int64(s.get(), 2);
      camera.height = sqlite3_column_int64(s.get(), 3);
      const int bytes = sqlite3_column_bytes(s.get(), 4);
      const void* blob = sqlite3_column_blob(s.get(), 4);
      if (bytes < 0 || bytes % 8 != 0 || bytes > 16 * 8) {
        throw InputError(path + ": camera " + std::to_string(camera.camera_id) +
                         ": params blob of " + std::to_string(bytes) +
                         " bytes is not 0 to 16 doubles");
      }
      camera.params.resize(static_cast<size_t>(bytes) / 8);
      if (bytes > 0) std::memcpy(camera.params.data(), blob, static_cast<size_t>(bytes));
      camera.prior_focal_length = sqlite3_column_int(s.get(), 5) != 0;
      out.cameras.push_back(std::move(camera));
    }
  }
  {
    Statement s = Prepare(db.get(), path,
                          "SELECT count(*), coalesce(sum(rows), 0) FROM two_view_geometries "
                          "WHERE rows > 0");
    if (Step(db.get(), s.get(), path)) {
      out.num_verified_pairs = sqlite3_column_int64(s.get(), 0);
      out.num_inlier_matches = sqlite3_column_int64(s.get(), 1);
    }
  }
  return out;
}

ColmapDbCamera ColmapCameraFor(const Intrinsics& k) {
  ColmapDbCamera camera;
  camera.width = k.width;
  camera.height = k.height;
  camera.prior_focal_length = true;
  if (!k.HasDistortion()) {
    camera.model = kPinhole;
    camera.params = {k.fx, k.fy, k.cx, k.cy};
  } else if (k.k3 == 0) {
    camera.model = kOpenCv;
    camera.params = {k.fx, k.fy, k.cx, k.cy, k.k1, k.k2, k.p1, k.p2};
  } else {
    camera.model = kFullOpenCv;
    camera.params = {k.fx, k.fy, k.cx, k.cy, k.k1, k.k2, k.p1, k.p2, k.k3, 0, 0, 0};
  }
  return camera;
}

void WriteColmapDatabaseCameras(const std::string& path,
                                const std::vector<ColmapDbCamera>& cameras) {
  SqliteDb db = OpenDatabase(path, true);
  Execute(db.get(), path, "BEGIN");
  Statement s = Prepare(db.get(), path,
                        "UPDATE cameras SET model = ?, width = ?, height = ?, params = ?, "
                        "prior_focal_length = ? WHERE camera_id = ?");
  for (const ColmapDbCamera& c : cameras) {
    sqlite3_reset(s.get());
    sqlite3_bind_int(s.get(), 1, c.model);
    sqlite3_bind_int64(s.get(), 2, c.width);
    sqlite3_bind_int64(s.get(), 3, c.height);
    sqlite3_bind_blob(s.get(), 4, c.params.data(), static_cast<int>(c.params.size() * 8),
                      SQLITE_TRANSIENT);
    sqlite3_bind_int(s.get(), 5, c.prior_focal_length ? 1 : 0);
    sqlite3_bind_int64(s.get(), 6, c.camera_id);
    Step(db.get(), s.get(), path);
    if (sqlite3_changes(db.get()) != 1) {
      throw InputError(path + ": camera " + std::to_string(c.camera_id) +
                       " is not in the database");
    }
  }
  s.reset();
  Execute(db.get(), path, "COMMIT");
}

// ---- model and id mapping -------------------------------------------------------------------

std::vector<std::string> ColmapWorkspaceNames(const Scene& scene) {
  std::vector<std::string> names(scene.views.size());
  std::set<std::string> used;
  // Plain names first, so a generated name can never take a view's own name.
  std::vector<bool> plain(scene.views.size(), false);
  std::map<std::string, int> counts;
  for (const View& v : scene.views) ++counts[v.name];
  for (size_t i = 0; i < scene.views.size(); ++i) {
    const std::string& name = scene.views[i].name;
    if (SafeRelativeName(name) && counts[name] == 1) {
      names[i] = name;
      plain[i] = true;
      used.insert(name);
    }
  }
  for (size_t i = 0; i < scene.views.size(); ++i) {
    if (plain[i]) continue;
    std::string ext = fs::path(scene.views[i].image_path.empty() ? scene.views[i].name
                                                                 : scene.views[i].image_path)
                          .extension()
                          .string();
    if (!SafeRelativeName("x" + ext) || ext.size() > 10) ext.clear();
    std::string name = fmt::format("ms_view_{:05d}{}", i, ext);
    for (int k = 1; used.count(name); ++k) name = fmt::format("ms_view_{:05d}_{}{}", i, k, ext);
    names[i] = name;
    used.insert(name);
  }
  return names;
}

ColmapIdMap MatchDatabaseToViews(const Scene& scene, const std::vector<std::string>& names,
                                 const ColmapDatabase& db, const std::string& db_name) {
  if (names.size() != scene.views.size()) {
    throw InternalError("MatchDatabaseToViews: " + std::to_string(names.size()) + " names for " +
                        std::to_string(scene.views.size()) + " views");
  }
  std::unordered_map<std::string, size_t> view_of_name;
  for (size_t i = 0; i < names.size(); ++i) view_of_name[names[i]] = i;
  ColmapIdMap ids;
  ids.image_id.assign(scene.views.size(), -1);
  ids.camera_id.assign(scene.views.size(), -1);
  for (const ColmapDbImage& image : db.images) {
    const auto it = view_of_name.find(image.name);
    if (it == view_of_name.end()) {
      throw InternalError(db_name + ": image " + std::to_string(image.image_id) + " '" +
                          image.name + "' is not a view of the scene");
    }
    if (ids.image_id[it->second] >= 0) {
      throw InternalError(db_name + ": image name '" + image.name + "' appears twice");
    }
    ids.image_id[it->second] = image.image_id;
    ids.camera_id[it->second] = image.camera_id;
  }
  std::unordered_map<int64_t, size_t> first_view_of_camera;
  for (size_t i = 0; i < scene.views.size(); ++i) {
    const View& v = scene.views[i];
    if (ids.image_id[i] < 0) {
      throw InputError((v.image_path.empty() ? v.name : v.image_path) +
                       ": colmap did not take in the image of view " + std::to_string(i) + " ('" +
                       v.name + "'): it could not read it");
    }
    const auto [it, inserted] = first_view_of_camera.emplace(ids.camera_id[i], i);
    if (!inserted && !(scene.views[it->second].intrinsics == v.intrinsics)) {
      throw InternalError(db_name + ": views " + std::to_string(it->second) + " and " +
                          std::to_string(i) + " share camera " + std::to_string(ids.camera_id[i]) +
                          " but differ in intrinsics");
    }
  }
  return ids;
}

ColmapFiles MakeKnownPoseModel(const Scene& scene, const std::vector<std::string>& names,
                               const ColmapIdMap& ids) {
  ColmapFiles files;
  files.cameras_name = "cameras.txt";
  files.images_name = "images.txt";
  files.points_name = "points3D.txt";
  files.cameras = "# CAMERA_ID, MODEL, WIDTH, HEIGHT, PARAMS[] (known intrinsics)\n";
  files.images =
      "# IMAGE_ID, QW, QX, QY, QZ, TX, TY, TZ, CAMERA_ID, NAME (known poses)\n"
      "# POINTS2D[] left empty: colmap takes the keypoints from the database\n";
  files.points = "# no points: point_triangulator makes them\n";
  std::set<int64_t> cameras_written;
  // Image ids in ascending order, so the file reads like colmap's own.
  std::vector<size_t> order(scene.views.size());
  for (size_t i = 0; i < order.size(); ++i) order[i] = i;
  std::sort(order.begin(), order.end(),
            [&](size_t a, size_t b) { return ids.image_id[a] < ids.image_id[b]; });
  for (const size_t i : order) {
    const View& v = scene.views[i];
    if (cameras_written.insert(ids.camera_id[i]).second) {
      const ColmapDbCamera c = ColmapCameraFor(v.intrinsics);
      files.cameras += fmt::format("{} {} {} {} {}\n", ids.camera_id[i], ModelName(c.model),
                                   c.width, c.height, JoinParams(c.params, " "));
    }
    const Eigen::Vector4d q = QuaternionFromRotation(v.R);
    files.images += fmt::format("{} {} {} {} {} {} {} {} {} {}\n\n", ids.image_id[i], Exact(q[0]),
                                Exact(q[1]), Exact(q[2]), Exact(q[3]), Exact(v.t.x()),
                                Exact(v.t.y()), Exact(v.t.z()), ids.camera_id[i], names[i]);
  }
  return files;
}

Scene AttachTriangulatedPoints(const Scene& cameras, const std::vector<std::string>& names,
                               const Scene& triangulated, ColmapTriangulateResult* result) {
  std::unordered_map<std::string, int32_t> view_of_name;
  for (size_t i = 0; i < names.size(); ++i) view_of_name[names[i]] = static_cast<int32_t>(i);
  std::vector<int32_t> remap(triangulated.views.size(), -1);
  std::vector<bool> seen(cameras.views.size(), false);
  double rotation_change = 0, translation_change = 0;
  for (size_t j = 0; j < triangulated.views.size(); ++j) {
    const View& tv = triangulated.views[j];
    const auto it = view_of_name.find(tv.name);
    if (it == view_of_name.end() || seen[it->second]) {
      throw InternalError(triangulated.source + ": image '" + tv.name +
                          "' is not a view of the scene, or appears twice");
    }
    seen[it->second] = true;
    remap[j] = it->second;
    const View& v = cameras.views[it->second];
    rotation_change = std::max(rotation_change, (tv.R - v.R).norm());
    translation_change =
        std::max(translation_change, (tv.t - v.t).norm() / std::max(1.0, v.t.norm()));
    const double k_change = IntrinsicsChange(tv.intrinsics, v.intrinsics);
    if (k_change > 1e-9) {
      throw InternalError(fmt::format(
          "{}: colmap changed the intrinsics of view '{}' (relative change {:.3g}); they must "
          "stay fixed",
          triangulated.source, tv.name, k_change));
    }
  }
  for (size_t i = 0; i < seen.size(); ++i) {
    if (!seen[i]) {
      throw InternalError(triangulated.source + ": view '" + names[i] +
                          "' is missing from colmap's model");
    }
  }
  if (rotation_change > 1e-6 || translation_change > 1e-6) {
    throw InternalError(fmt::format(
        "{}: colmap moved a known pose (rotation change {:.3g}, translation change {:.3g}); "
        "poses must stay fixed",
        triangulated.source, rotation_change, translation_change));
  }
  if (result) {
    result->max_rotation_change = rotation_change;
    result->max_translation_change = translation_change;
  }
  Scene scene;
  scene.views = cameras.views;
  scene.source = cameras.source;
  scene.points.reserve(triangulated.points.size());
  for (const ScenePoint& p : triangulated.points) {
    ScenePoint point = p;
    for (Observation& o : point.observations) {
      if (o.view < 0 || static_cast<size_t>(o.view) >= remap.size()) {
        throw InternalError(triangulated.source + ": observation of an unknown view");
      }
      o.view = remap[o.view];
    }
    scene.points.push_back(std::move(point));
  }
  scene.NormalizeObservations();
  return scene;
}

std::string ColmapImageError(const std::string& extraction_output, const std::string& name) {
  size_t at = 0;
  while ((at = extraction_output.find("Name:", at)) != std::string::npos) {
    const size_t line_end = std::min(extraction_output.find('\n', at), extraction_output.size());
    std::string line = extraction_output.substr(at + 5, line_end - at - 5);
    line.erase(0, line.find_first_not_of(' '));
    at = line_end;
    if (line != name) continue;
    const size_t next_end =
        std::min(extraction_output.find('\n', line_end + 1), extraction_output.size());
    if (line_end >= extraction_output.size()) return "";
    std::string next = extraction_output.substr(line_end + 1, next_end - line_end - 1);
    const size_t error = next.find("ERROR:");
    if (error == std::string::npos) return "";
    next = next.substr(error + 6);
    next.erase(0, next.find_first_not_of(' '));
    return next;
  }
  return "";
}

std::string ParseColmapVersion(const std::string& help_output) {
  const size_t at = help_output.find("COLMAP ");
  if (at == std::string::npos) return "";
  size_t end = at + 7;
  while (end < help_output.size() &&
         (std::isdigit(static_cast<unsigned char>(help_output[end])) || help_output[end] == '.')) {
    ++end;
  }
  if (end == at + 7) return "";
  return help_output.substr(at, end - at);
}

// ---- the route ------------------------------------------------------------------------------

namespace {

// Every view has its image: colmap extracts features from them.
void CheckViewsHaveImages(const Scene& cameras, const std::string& source) {
  if (cameras.views.size() < 2) {
    throw InputError(source + ": point_triangulator needs at least two views, the scene has " +
                     std::to_string(cameras.views.size()));
  }
  std::error_code ec;
  for (size_t i = 0; i < cameras.views.size(); ++i) {
    const View& v = cameras.views[i];
    if (v.image_path.empty() || !fs::is_regular_file(v.image_path, ec)) {
      throw InputError(source + ": view " + std::to_string(i) + " ('" + v.name + "'): image file " +
                       (v.image_path.empty() ? "unknown" : v.image_path) +
                       " not found (give the image folder with --images)");
    }
  }
}

std::string FindColmapOrThrow(const std::string& colmap) {
  const std::string path = FindExecutable(colmap);
  if (path.empty()) {
    throw InputError(
        "colmap: '" + colmap + "' " +
        (colmap.find('/') == std::string::npos ? "is not in PATH" : "is not an executable") +
        "; install the Debian package `colmap` (sudo apt-get install colmap, or deploy/setup.sh) "
        "or give its path with --colmap");
  }
  return path;
}

// A fresh temporary folder, or the given one emptied of an earlier route's files. Absolute.
fs::path PrepareWorkspace(const std::string& given) {
  std::error_code ec;
  if (given.empty()) {
    std::string pattern = (fs::temp_directory_path() / "manisweep-colmap-XXXXXX").string();
    if (!::mkdtemp(pattern.data())) {
      throw InputError(pattern +
                       ": cannot create the temporary colmap workspace: " + strerror(errno));
    }
    return fs::absolute(pattern);
  }
  const fs::path workspace = given;
  fs::create_directories(workspace, ec);
  if (ec || !fs::is_directory(workspace, ec)) {
    throw InputError(given + ": cannot create the colmap workspace directory");
  }
  for (const char* old :
       {"database.db", "database.db-journal", "database.db-wal", "database.db-shm", "images",
        "image_list.txt", "model_in", "model_out", "colmap.log"}) {
    fs::remove_all(workspace / old, ec);
    if (ec) throw InputError((workspace / old).string() + ": cannot remove: " + ec.message());
  }
  return fs::absolute(workspace);
}

// What the stages share: the scene, the workspace's files, colmap, the result being filled.
struct ColmapRoute {
  const Scene& cameras;
  const ColmapTriangulateOptions& options;
  ColmapTriangulateResult& result;
  fs::path workspace;
  ColmapRunner& colmap;
  std::vector<std::string> names;  // the views' names in the workspace (ColmapWorkspaceNames)
  ColmapIdMap ids;                 // the database's ids of the views (after ExtractFeatures)

  fs::path Database() const { return workspace / "database.db"; }
  fs::path Images() const { return workspace / "images"; }
  fs::path ModelIn() const { return workspace / "model_in"; }
  fs::path ModelOut() const { return workspace / "model_out"; }
  int64_t NumViews() const { return static_cast<int64_t>(cameras.views.size()); }
  std::string Threads() const { return std::to_string(options.threads); }

  void Timed(const std::string& stage, const std::function<void()>& body) {
    Timer timer;
    body();
    result.stage_times.push_back({stage, timer.Seconds()});
    spdlog::info("{}: {:.1f} s", stage, result.stage_times.back().seconds);
  }
};

void CheckColmapVersion(ColmapRoute& route) {
  const std::string help = route.colmap.Run("-h", {});
  route.result.colmap_version = ParseColmapVersion(help);
  spdlog::info(
      "colmap: {} ({})",
      route.result.colmap_version.empty() ? "unknown version" : route.result.colmap_version,
      route.result.colmap_path);
  if (route.result.colmap_version.rfind("COLMAP 3.", 0) != 0) {
    spdlog::warn(
        "colmap: the options used here were checked with COLMAP 3.8 (Debian 12); "
        "this one reports '{}'",
        route.result.colmap_version);
  }
}

// Images: links named as the views (see ColmapWorkspaceNames), listed explicitly so colmap
// sees exactly the scene's views.
void LinkImages(ColmapRoute& route) {
  std::error_code ec;
  std::string list;
  for (size_t i = 0; i < route.names.size(); ++i) {
    const fs::path link = route.Images() / route.names[i];
    fs::create_directories(link.parent_path(), ec);
    fs::create_symlink(fs::absolute(route.cameras.views[i].image_path), link, ec);
    if (ec) throw InputError(link.string() + ": cannot create image link: " + ec.message());
    list += route.names[i] + "\n";
  }
  WriteFileAtomically(
      route.workspace / "image_list.txt", [&](std::ostream& out) { out << list; }, false);
}

// 1. SIFT features on the CPU, one camera per image with the first view's intrinsics; the
//    database's cameras get every view's own intrinsics right after.
void ExtractFeatures(ColmapRoute& route) {
  const ColmapDbCamera first = ColmapCameraFor(route.cameras.views[0].intrinsics);
  std::string extraction_output;
  route.Timed("feature_extractor", [&] {
    extraction_output =
        route.colmap.Run("feature_extractor",
                         {"--database_path",
                          route.Database().string(),
                          "--image_path",
                          route.Images().string(),
                          "--image_list_path",
                          (route.workspace / "image_list.txt").string(),
                          "--ImageReader.camera_model",
                          ModelName(first.model),
                          "--ImageReader.camera_params",
                          JoinParams(first.params, ","),
                          "--ImageReader.single_camera",
                          "0",
                          "--SiftExtraction.use_gpu",
                          "0",
                          "--SiftExtraction.max_image_size",
                          std::to_string(route.options.max_image_size),
                          "--SiftExtraction.num_threads",
                          route.Threads(),
                          "--log_to_stderr",
                          "1"},
                         [](const std::string& line, StageMonitor& m) {
                           int64_t done = 0, total = 0;
                           if (ParseFraction(line, "Processed file [", &done, &total)) {
                             m.Report(done, total, "images");
                           }
                         });
  });
  const std::string database = route.Database().string();
  const ColmapDatabase db = ReadColmapDatabase(database);
  ColmapIdMap ids;
  try {
    ids = MatchDatabaseToViews(route.cameras, route.names, db, database);
  } catch (const InputError& e) {
    // Add what colmap said about the image ("Name: <name>", then "ERROR: ...").
    std::string said;
    for (size_t i = 0; i < route.names.size() && said.empty(); ++i) {
      said = ColmapImageError(extraction_output, route.names[i]);
    }
    throw InputError(std::string(e.what()) + (said.empty() ? "" : " (colmap: " + said + ")"));
  }
  std::vector<ColmapDbCamera> known;
  std::set<int64_t> done;
  for (size_t i = 0; i < route.cameras.views.size(); ++i) {
    if (!done.insert(ids.camera_id[i]).second) continue;
    known.push_back(ColmapCameraFor(route.cameras.views[i].intrinsics));
    known.back().camera_id = ids.camera_id[i];
  }
  WriteColmapDatabaseCameras(database, known);
  int64_t without_features = 0;
  for (const ColmapDbImage& image : db.images) {
    route.result.num_keypoints += image.num_keypoints;
    if (image.num_keypoints == 0) ++without_features;
  }
  spdlog::info("colmap: {} SIFT features in {} views ({:.0f} per view)", route.result.num_keypoints,
               route.NumViews(),
               static_cast<double>(route.result.num_keypoints) / route.NumViews());
  if (without_features > 0) spdlog::warn("colmap: {} views have no features", without_features);
  route.ids = ids;
}

// 2. Matching with geometric verification under the known intrinsics.
void MatchFeatures(ColmapRoute& route) {
  const std::string matcher = route.options.matcher + "_matcher";
  route.Timed(matcher, [&] {
    route.colmap.Run(matcher,
                     {"--database_path", route.Database().string(), "--SiftMatching.use_gpu", "0",
                      "--SiftMatching.num_threads", route.Threads(), "--log_to_stderr", "1"},
                     [](const std::string& line, StageMonitor& m) {
                       long long a = 0, b = 0, c = 0, d = 0;
                       int64_t x = 0, y = 0;
                       const size_t at = line.find("Matching block [");
                       if (at != std::string::npos &&
                           std::sscanf(line.c_str() + at, "Matching block [%lld/%lld, %lld/%lld]",
                                       &a, &b, &c, &d) == 4 &&
                           b > 0 && d > 0) {
                         m.Report((a - 1) * d + c, b * d, "blocks");
                       } else if (ParseFraction(line, "Matching image [", &x, &y)) {
                         m.Report(x, y, "images");
                       }
                     });
  });
  const ColmapDatabase db = ReadColmapDatabase(route.Database().string());
  route.result.num_verified_pairs = db.num_verified_pairs;
  route.result.num_inlier_matches = db.num_inlier_matches;
  spdlog::info("colmap: {} of {} image pairs verified, {} inlier matches", db.num_verified_pairs,
               route.NumViews() * (route.NumViews() - 1) / 2, db.num_inlier_matches);
  if (db.num_verified_pairs == 0) {
    spdlog::warn("colmap: no image pair has verified matches; no points can be triangulated");
  }
}

// 3. The known cameras as a model with the database's ids, then triangulation with them fixed.
void TriangulatePoints(ColmapRoute& route) {
  const ColmapFiles model = MakeKnownPoseModel(route.cameras, route.names, route.ids);
  std::error_code ec;
  fs::create_directories(route.ModelIn(), ec);
  fs::create_directories(route.ModelOut(), ec);
  for (const auto& [name, text] : {std::pair{model.cameras_name, &model.cameras},
                                   {model.images_name, &model.images},
                                   {model.points_name, &model.points}}) {
    WriteFileAtomically(
        route.ModelIn() / name, [&](std::ostream& out) { out << *text; }, false);
  }
  const int64_t num_views = route.NumViews();
  route.Timed("point_triangulator", [&] {
    route.colmap.Run(
        "point_triangulator",
        {"--database_path", route.Database().string(), "--image_path", route.Images().string(),
         "--input_path", route.ModelIn().string(), "--output_path", route.ModelOut().string(),
         "--Mapper.ba_refine_focal_length", "0", "--Mapper.ba_refine_principal_point", "0",
         "--Mapper.ba_refine_extra_params", "0", "--Mapper.num_threads", route.Threads(),
         "--log_to_stderr", "1"},
        [num_views](const std::string& line, StageMonitor& m) {
          if (line.rfind("Triangulating image #", 0) == 0) {
            const size_t open = line.rfind('(');
            if (open != std::string::npos) {
              m.Report(std::atoll(line.c_str() + open + 1) + 1, num_views, "images");
            }
          } else if (line == "Retriangulation" || line == "Bundle adjustment" ||
                     line == "Extracting colors") {
            m.Phase(line == "Bundle adjustment" ? "bundle adjustment of the points "
                                                  "(poses fixed)"
                                                : line);
          }
        });
  });
}

// 4. Import: the triangulated points attached to the given cameras.
void ImportModel(ColmapRoute& route) {
  route.Timed("import", [&] {
    const std::string model_dir = FindColmapModelDir(route.ModelOut().string());
    if (model_dir.empty()) {
      throw InternalError(route.ModelOut().string() + ": colmap point_triangulator wrote no model");
    }
    SceneReadOptions read;
    read.read_image_sizes = false;
    const Scene triangulated = ReadColmapModel(model_dir, ColmapModelIsBinary(model_dir), read);
    route.result.scene =
        AttachTriangulatedPoints(route.cameras, route.names, triangulated, &route.result);
    route.result.scene.Validate();
  });
}

}  // namespace

ColmapTriangulateResult TriangulateWithColmap(const Scene& cameras,
                                              const ColmapTriangulateOptions& options) {
  options.Check();
  CheckViewsHaveImages(cameras, cameras.source.empty() ? "scene" : cameras.source);
  ColmapTriangulateResult result;
  result.colmap_path = FindColmapOrThrow(options.colmap);
  const bool temporary = options.workspace.empty();
  const fs::path workspace = PrepareWorkspace(options.workspace);
  const bool keep = !temporary || options.keep_workspace;
  WorkspaceGuard guard(workspace, !keep);
  spdlog::info("colmap workspace: {}{}", workspace.string(),
               keep ? "" : " (removed at the end; --keep-workspace keeps it)");
  const fs::path log_path = workspace / "colmap.log";
  { std::ofstream touch(log_path); }
  ColmapRunner colmap(result.colmap_path, log_path, keep);
  ColmapRoute route{cameras, options, result, workspace, colmap, ColmapWorkspaceNames(cameras), {}};
  CheckColmapVersion(route);
  LinkImages(route);
  ExtractFeatures(route);
  MatchFeatures(route);
  TriangulatePoints(route);
  ImportModel(route);
  return result;
}

}  // namespace ms
