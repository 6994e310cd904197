// 100 MB of garbage through every scene reader and the image header parser. Each read runs in a
// child process whose address space is capped (RLIMIT_AS) at its size at fork time plus 600 MB:
// a reader that trusted a count from the file, or amplified the input, would die of bad_alloc
// instead of failing with InputError. The garbage is generated here, never committed.
#include <gtest/gtest.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>

#include "base/error.h"
#include "base/file_util.h"
#include "base/log.h"
#include "scene/image_io.h"
#include "scene/scene_io.h"

namespace ms {
namespace {

#if defined(__SANITIZE_ADDRESS__)
constexpr bool kSanitized = true;
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
constexpr bool kSanitized = true;
#else
constexpr bool kSanitized = false;
#endif
#else
constexpr bool kSanitized = false;
#endif

namespace fs = std::filesystem;

constexpr size_t kGarbageBytes = size_t{100} << 20;
constexpr size_t kHeadroomBytes = size_t{600} << 20;

std::string Garbage(size_t bytes, uint64_t seed) {
  std::string out(bytes, '\0');
  uint64_t x = seed;
  for (size_t i = 0; i + 8 <= bytes; i += 8) {
    x ^= x << 13;
    x ^= x >> 7;
    x ^= x << 17;
    std::memcpy(&out[i], &x, 8);
  }
  return out;
}

void WriteFile(const fs::path& path, const std::string& prefix, const std::string& body) {
  fs::create_directories(path.parent_path());
  std::ofstream out(path, std::ios::binary);
  out.write(prefix.data(), prefix.size());
  out.write(body.data(), body.size());
  ASSERT_TRUE(out.good()) << path;
}

uint64_t AddressSpaceBytes() {
  std::ifstream statm("/proc/self/statm");
  uint64_t pages = 0;
  statm >> pages;
  return pages * static_cast<uint64_t>(::sysconf(_SC_PAGESIZE));
}

struct Outcome {
  int exit_code = -1;
  long max_rss_kb = 0;
};

// Runs `read` in a child with a capped address space: exit 2 = InputError, 3 = bad_alloc,
// 4 = another exception, 0 = no error.
Outcome RunCapped(const std::function<void()>& read) {
  const uint64_t limit = AddressSpaceBytes() + kHeadroomBytes;
  const pid_t pid = ::fork();
  if (pid == 0) {
    struct rlimit cap = {limit, limit};
    ::setrlimit(RLIMIT_AS, &cap);
    int code = 0;
    try {
      read();
    } catch (const InputError&) {
      code = 2;
    } catch (const std::bad_alloc&) {
      code = 3;
    } catch (...) {
      code = 4;
    }
    std::fflush(nullptr);
    ::_exit(code);
  }
  Outcome outcome;
  int status = 0;
  struct rusage usage {};
  ::wait4(pid, &status, 0, &usage);
  outcome.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
  outcome.max_rss_kb = usage.ru_maxrss;
  return outcome;
}

TEST(Garbage, HundredMegabytesThroughEveryReaderFailCleanly) {
  spdlog::set_level(spdlog::level::err);
  const fs::path dir = fs::temp_directory_path() / ("ms_garbage_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  std::string garbage = Garbage(kGarbageBytes, 0x9E3779B97F4A7C15ull);
  const std::string source = std::string(MS_SOURCE_DIR) + "/tests/data/";
  // One file of pure garbage, linked under every name; a few readers also get garbage after a
  // valid-looking start, so they parse further before failing.
  WriteFile(dir / "garbage", "", garbage);
  const auto link = [&](const fs::path& name) {
    fs::create_directories(name.parent_path());
    fs::create_symlink(dir / "garbage", name);
  };
  link(dir / "g.nvm");
  link(dir / "bundler/bundle.out");
  WriteFile(dir / "bundler/list.txt", "", "a.png\nb.png\n");
  link(dir / "sfm_data.json");
  link(dir / "g_par.txt");
  for (const char* f : {"cameras.txt", "images.txt", "points3D.txt"}) link(dir / "text" / f);
  for (const char* f : {"cameras.bin", "images.bin", "points3D.bin"}) link(dir / "bin" / f);
  link(dir / "strecha/a.png.camera");
  link(dir / "image.png");
  WriteFile(dir / "header.nvm", "NVM_V3\n\n3\n", garbage);
  fs::create_directories(dir / "text2");
  fs::copy_file(source + "colmap/text/cameras.txt", dir / "text2/cameras.txt");
  WriteFile(dir / "text2/images.txt", "1 1 0 0 0 0 0 0 1 a.png\n", garbage);
  link(dir / "text2/points3D.txt");
  fs::create_directories(dir / "bin2");
  fs::copy_file(source + "colmap/bin/cameras.bin", dir / "bin2/cameras.bin");
  std::string count(8, '\0');
  const uint64_t many = kGarbageBytes / 80;  // passes CheckCount, then hits garbage
  std::memcpy(&count[0], &many, 8);
  WriteFile(dir / "bin2/images.bin", count, garbage);
  link(dir / "bin2/points3D.bin");
  WriteFile(dir / "image.jpg", "\xFF\xD8", garbage);
  std::string().swap(garbage);  // the children's memory is measured: do not lend them this

  SceneReadOptions options;
  options.image_dir = source + "images";
  const std::pair<std::string, SceneFormat> scenes[] = {
      {"g.nvm", SceneFormat::kNvm},
      {"header.nvm", SceneFormat::kNvm},
      {"bundler/bundle.out", SceneFormat::kBundler},
      {"sfm_data.json", SceneFormat::kOpenMvg},
      {"g_par.txt", SceneFormat::kMiddlebury},
      {"text", SceneFormat::kColmapText},
      {"text2", SceneFormat::kColmapText},
      {"bin", SceneFormat::kColmapBinary},
      {"bin2", SceneFormat::kColmapBinary},
      {"strecha", SceneFormat::kStrecha},
  };
  long worst_rss_kb = 0;
  const Timer timer;
  for (const auto& [name, format] : scenes) {
    const Outcome outcome = RunCapped(
        [&, name = name, format = format] { ReadScene((dir / name).string(), options, format); });
    EXPECT_EQ(outcome.exit_code, 2) << name << " (3 = bad_alloc under the address-space cap)";
    worst_rss_kb = std::max(worst_rss_kb, outcome.max_rss_kb);
  }
  for (const char* image : {"image.png", "image.jpg"}) {
    const Outcome outcome = RunCapped([&] { ReadImageSize((dir / image).string()); });
    EXPECT_EQ(outcome.exit_code, 2) << image;
  }
  // The input itself is 100 MB and is held once or twice (file contents, parser copy). ASan's
  // shadow memory and quarantine inflate RSS, so the bound holds for normal builds only.
  if (!kSanitized) {
    EXPECT_LT(worst_rss_kb, 450 * 1024) << "peak RSS of a reader in KB";
  }
  RecordProperty("worst_peak_rss_mb", std::to_string(worst_rss_kb / 1024));
  RecordProperty("seconds", std::to_string(timer.Seconds()));
  fs::remove_all(dir);
}

}  // namespace
}  // namespace ms
