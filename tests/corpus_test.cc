// Malformed inputs (tests/corpus, see make_corpus.py): every case must give InputError whose
// message is one line naming a file of the case; through the `manisweep convert` binary, exit
// code 2 and exactly one line on stderr.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "base/error.h"
#include "base/file_util.h"
#include "scene/image_io.h"
#include "scene/scene_io.h"

namespace ms {
namespace {

namespace fs = std::filesystem;

const std::string kCorpus = std::string(MS_SOURCE_DIR) + "/tests/corpus";
const std::string kImages = std::string(MS_SOURCE_DIR) + "/tests/data/images";

struct Case {
  std::string format;  // ParseSceneFormat name
  std::string input;   // path to pass to ReadScene
  std::string name;
};

bool EndsWith(const std::string& s, const std::string& suffix) {
  return s.size() >= suffix.size() &&
         s.compare(s.size() - suffix.size(), suffix.size(), suffix) == 0;
}

std::vector<Case> SceneCases() {
  std::vector<Case> cases;
  for (const char* format :
       {"colmap-text", "colmap-binary", "nvm", "bundler", "openmvg", "strecha", "middlebury"}) {
    std::vector<fs::path> entries;
    for (const auto& e : fs::directory_iterator(kCorpus + "/" + format))
      entries.push_back(e.path());
    std::sort(entries.begin(), entries.end());
    for (const fs::path& entry : entries) {
      const std::string f = format;
      const std::string file = entry.filename().string();
      std::string input;
      if (f == "colmap-text" || f == "colmap-binary" || f == "strecha") {
        if (fs::is_directory(entry)) input = entry.string();
      } else if (f == "bundler") {
        if (fs::is_directory(entry)) input = (entry / "bundle.out").string();
      } else if (f == "nvm"       ? EndsWith(file, ".nvm")
                 : f == "openmvg" ? EndsWith(file, ".json")
                                  : EndsWith(file, "_par.txt")) {
        input = entry.string();
      }
      if (!input.empty()) cases.push_back({f, input, f + "/" + file});
    }
  }
  return cases;
}

SceneReadOptions CorpusOptions() {
  SceneReadOptions options;
  options.image_dir = kImages;
  return options;
}

TEST(Corpus, EveryCaseIsAnInputErrorNamingItsFile) {
  const std::vector<Case> cases = SceneCases();
  EXPECT_GE(cases.size(), 90u);
  for (const Case& c : cases) {
    SCOPED_TRACE(c.name);
    try {
      ReadScene(c.input, CorpusOptions(), ParseSceneFormat(c.format));
      ADD_FAILURE() << "no error for " << c.name;
    } catch (const InputError& e) {
      const std::string message = e.what();
      EXPECT_NE(message.find(kCorpus + "/" + c.format + "/"), std::string::npos) << message;
      EXPECT_EQ(message.find('\n'), std::string::npos) << message;
      EXPECT_EQ(message.find('\x1b'), std::string::npos) << message;
      EXPECT_LT(message.size(), 600u) << message;
    }
  }
}

TEST(Corpus, ImageHeaders) {
  int count = 0;
  for (const auto& e : fs::directory_iterator(kCorpus + "/image")) {
    SCOPED_TRACE(e.path().string());
    ++count;
    try {
      ReadImageSize(e.path().string());
      ADD_FAILURE() << "no error";
    } catch (const InputError& error) {
      EXPECT_EQ(std::string(error.what()).rfind(e.path().string(), 0), 0u) << error.what();
    }
    const std::string bytes = ReadFileToString(e.path());
    EXPECT_THROW(ParseImageSize("x", bytes), InputError);
  }
  EXPECT_GE(count, 9);
}

// Runs the binary; returns the exit code and fills `err` with stderr.
int RunConvert(const Case& c, const std::string& out_dir, std::string* err) {
  const std::string err_file = out_dir + "/stderr.txt";
  const std::string command = "'" MANISWEEP_BINARY "' --log-level error convert --input '" +
                              c.input + "' --from " + c.format + " --image-dir '" + kImages +
                              "' --output '" + out_dir + "/out.nvm' > /dev/null 2> '" + err_file +
                              "'";
  const int status = std::system(command.c_str());
  std::ifstream in(err_file);
  std::stringstream buffer;
  buffer << in.rdbuf();
  *err = buffer.str();
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

TEST(Corpus, BinaryExitsWithTwoAndOneLine) {
  // Two cases per format plus the one with control bytes in a name: every run costs a process
  // start, and main()'s handling is the same for all InputErrors (whose one-line form the test
  // above checks for every case).
  const fs::path out_dir = fs::temp_directory_path() / ("ms_corpus_" + std::to_string(::getpid()));
  fs::create_directories(out_dir);
  std::map<std::string, int> taken;
  int runs = 0;
  for (const Case& c : SceneCases()) {
    if (taken[c.format]++ >= 2 && c.name != "nvm/name_with_control_bytes.nvm") continue;
    SCOPED_TRACE(c.name);
    std::string err;
    EXPECT_EQ(RunConvert(c, out_dir.string(), &err), kExitBadInput) << err;
    EXPECT_EQ(std::count(err.begin(), err.end(), '\n'), 1) << err;
    EXPECT_EQ(err.rfind("manisweep: error: ", 0), 0u) << err;
    EXPECT_NE(err.find(kCorpus + "/" + c.format + "/"), std::string::npos) << err;
    EXPECT_FALSE(fs::exists(out_dir / "out.nvm"));
    ++runs;
  }
  EXPECT_EQ(runs, 15);
  fs::remove_all(out_dir);
}

}  // namespace
}  // namespace ms
