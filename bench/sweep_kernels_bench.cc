// Pixel-hypotheses per second (pixels x offsets x neighbours) of the sweep kernels on the
// synthetic pyramid job (testing/sweep_test_scene.h: noise 0.01, the flat square at half height),
// default options (N = 20: 19 offsets, 2 neighbours, sigma = 8 px, 100 px tiles), swept at full
// size (max_image_dimension 0); every --sweep.* option of `reconstruct` changes them. Kernels run
// interleaved, round after round, so a noisy shared machine slows them alike; the median of the
// rounds is reported.
//
// Per kernel and size: hypotheses per second of wall time (what one worker delivers) and per
// second of process CPU time (per core), the stage seconds (CPU seconds, summed over threads)
// and the tile winners shared with the reference where it ran. Numbers: docs/design/performance.md.
//
//   sweep_kernels_bench [--sizes 640x480,1536x1024,3072x2048] [--kernels cpu,cpu:2,reference,glsl]
//                       [--rounds 3] [--output results.tsv] [--sweep.winners-must-move ...]
// "cpu:T" is the CPU kernel on T threads (default 1); "glsl" uses whatever GL context the
// machine has (llvmpipe on a CPU machine, the GPU where there is one).
#include <CLI/CLI.hpp>
#include <algorithm>
#include <cstdio>
#include <ctime>
#include <fstream>
#include <map>
#include <memory>
#include <opencv2/core/utility.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "app/option_registration.h"
#include "base/error.h"
#include "base/log.h"
#include "sweep/cpu_sweep.h"
#include "sweep/glsl_sweep.h"
#include "sweep/reference_sweep.h"
#include "testing/sweep_test_scene.h"

namespace ms {
namespace {

double ProcessCpuSeconds() {
  timespec t;
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
  return static_cast<double>(t.tv_sec) + 1e-9 * static_cast<double>(t.tv_nsec);
}

std::vector<std::string> Split(const std::string& s, char sep) {
  std::vector<std::string> parts;
  std::stringstream in(s);
  for (std::string part; std::getline(in, part, sep);) {
    if (!part.empty()) parts.push_back(part);
  }
  return parts;
}

struct KernelSpec {
  std::string label;  // as given: cpu, cpu:2, reference, glsl
  std::string name;
  int threads = 1;
};

struct Sample {
  double wall = 0, cpu = 0;
  SweepResult result;
};

double Median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v.empty() ? 0 : v[v.size() / 2];
}

int SameWinners(const SweepResult& reference, const SweepResult& other) {
  std::map<std::pair<float, float>, int> offsets;
  for (const SweepPoint& p : reference.points) offsets[{p.pixel.x(), p.pixel.y()}] = p.offset;
  int same = 0;
  for (const SweepPoint& p : other.points) {
    auto it = offsets.find({p.pixel.x(), p.pixel.y()});
    same += it != offsets.end() && it->second == p.offset;
  }
  return same;
}

int Usage(const std::string& error) {
  std::fprintf(stderr, "error: %s (see sweep_kernels_bench --help)\n", error.c_str());
  return 2;
}

int Main(int argc, char** argv) {
  std::string sizes_arg = "640x480,1536x1024,3072x2048", kernels_arg = "cpu,cpu:2,reference";
  std::string output;
  int rounds = 3;
  SweepOptions sweep;
  sweep.max_image_dimension = 0;  // full size unless asked
  CLI::App cli("Pixel-hypotheses per second of the sweep kernels (docs/design/performance.md)");
  cli.add_option("--sizes", sizes_arg, "image sizes, WxH,...")->capture_default_str();
  cli.add_option("--kernels", kernels_arg, "cpu, cpu:T (T threads), reference, glsl")
      ->capture_default_str();
  cli.add_option("--rounds", rounds, "rounds, kernels interleaved in each")
      ->check(CLI::Range(1, 1000))
      ->capture_default_str();
  cli.add_option("--output", output, "write the table as TSV to this file");
  app::AddOptionGroup(&cli, &sweep);
  try {
    cli.parse(argc, argv);
    sweep.Check();
  } catch (const CLI::ParseError& e) {
    return cli.exit(e);
  } catch (const InputError& e) {
    return Usage(e.what());
  }
  std::vector<std::pair<int, int>> sizes;
  for (const std::string& s : Split(sizes_arg, ',')) {
    int w = 0, h = 0;
    if (std::sscanf(s.c_str(), "%dx%d", &w, &h) != 2 || w < 16 || h < 16) {
      return Usage("bad size " + s);
    }
    sizes.emplace_back(w, h);
  }
  std::vector<KernelSpec> kernels;
  for (const std::string& k : Split(kernels_arg, ',')) {
    KernelSpec spec{k, k, 1};
    const size_t colon = k.find(':');
    if (colon != std::string::npos) {
      spec.name = k.substr(0, colon);
      spec.threads = std::atoi(k.c_str() + colon + 1);
    }
    if ((spec.name != "cpu" && spec.name != "reference" && spec.name != "glsl") ||
        spec.threads < 1) {
      return Usage("bad kernel " + k);
    }
    kernels.push_back(spec);
  }
  std::unique_ptr<GlslSweepKernel> glsl;
  for (const KernelSpec& k : kernels) {
    if (k.name == "glsl" && !glsl) {
      glsl = std::make_unique<GlslSweepKernel>();
      std::printf("GL: %s\n", glsl->gl_info().Summary().c_str());
    }
  }

  std::ostringstream table;
  table << "size\tkernel\tthreads\thyp_per_s_wall\thyp_per_s_cpu\twall_s\tcpu_s\traster_s\t"
           "reproject_s\tncc_s\treduce_s\tpoints\tsame_winners_as_reference\n";
  for (const auto& [width, height] : sizes) {
    SweepJob job = MakeBenchmarkSweepJob(width, height);
    job.options = sweep;
    std::map<std::string, std::vector<Sample>> samples;
    if (glsl) glsl->Run(job);  // warm-up: shader JIT, texture allocation
    for (int round = 0; round < rounds; ++round) {
      for (const KernelSpec& k : kernels) {
        cv::setNumThreads(k.threads);
        std::unique_ptr<SweepKernel> owned;
        SweepKernel* kernel = glsl.get();
        if (k.name == "cpu") kernel = (owned = std::make_unique<CpuSweepKernel>()).get();
        if (k.name == "reference")
          kernel = (owned = std::make_unique<ReferenceSweepKernel>()).get();
        Sample s;
        Timer timer;
        const double cpu0 = ProcessCpuSeconds();
        s.result = kernel->Run(job);
        s.cpu = ProcessCpuSeconds() - cpu0;
        s.wall = timer.Seconds();
        std::printf("%dx%d round %d %-10s %7.3f s wall %7.3f s cpu  %s\n", width, height, round,
                    k.label.c_str(), s.wall, s.cpu, s.result.stats.Summary().c_str());
        std::fflush(stdout);
        samples[k.label].push_back(std::move(s));
      }
    }
    const SweepResult* reference =
        samples.count("reference") ? &samples["reference"].front().result : nullptr;
    for (const KernelSpec& k : kernels) {
      const std::vector<Sample>& runs = samples[k.label];
      std::vector<double> wall, cpu;
      for (const Sample& s : runs) {
        wall.push_back(s.wall);
        cpu.push_back(s.cpu);
      }
      const SweepStats& st = runs.back().result.stats;
      const double hyp = static_cast<double>(st.hypotheses);
      table << width << "x" << height << "\t" << k.name << "\t"
            << (k.name == "glsl" ? "gl" : std::to_string(k.threads)) << "\t" << hyp / Median(wall)
            << "\t" << hyp / Median(cpu) << "\t" << Median(wall) << "\t" << Median(cpu) << "\t"
            << st.raster_s << "\t" << st.reproject_s << "\t" << st.ncc_s << "\t" << st.reduce_s
            << "\t" << runs.back().result.points.size() << "\t"
            << (reference ? std::to_string(SameWinners(*reference, runs.back().result)) + "/" +
                                std::to_string(reference->points.size())
                          : "-")
            << "\n";
    }
  }
  std::printf("\n%s", table.str().c_str());
  if (!output.empty()) {
    std::ofstream out(output);
    out << table.str();
    if (!out) {
      std::fprintf(stderr, "error: cannot write %s\n", output.c_str());
      return 1;
    }
  }
  return 0;
}

}  // namespace
}  // namespace ms

int main(int argc, char** argv) { return ms::Main(argc, argv); }
