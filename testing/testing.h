// Helpers for *_test.cc files only (header-only; gtest/gmock): a scratch directory and the
// check that bad input raises an InputError naming what is wrong.
#pragma once

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <atomic>
#include <filesystem>
#include <iostream>
#include <string>
#include <vector>

#include "base/error.h"

namespace ms::testing {

// A fresh, empty temporary directory, unique per process and instance (removed by the
// destructor).
class TempDir {
 public:
  explicit TempDir(const std::string& tag = "test") {
    static std::atomic<int> counter{0};
    path_ = std::filesystem::temp_directory_path() /
            ("ms_" + tag + "_" + std::to_string(::getpid()) + "_" + std::to_string(counter++));
    std::filesystem::remove_all(path_);
    std::filesystem::create_directories(path_);
  }
  ~TempDir() {
    std::error_code ec;
    std::filesystem::remove_all(path_, ec);
  }
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;
  std::string operator/(const std::string& name) const { return (path_ / name).string(); }
  const std::filesystem::path& path() const { return path_; }

 private:
  std::filesystem::path path_;
};

// Expects `f()` to throw an InputError whose message contains every fragment
// (MS_SHOW_ERRORS=1 prints the messages, to review their wording).
template <typename F>
void ExpectInputError(F&& f, const std::vector<std::string>& fragments) {
  try {
    f();
    ADD_FAILURE() << "no InputError thrown; expected one mentioning '"
                  << (fragments.empty() ? std::string() : fragments.front()) << "'";
  } catch (const InputError& e) {
    if (std::getenv("MS_SHOW_ERRORS")) std::cout << "  InputError: " << e.what() << "\n";
    for (const std::string& fragment : fragments) {
      EXPECT_THAT(e.what(), ::testing::HasSubstr(fragment));
    }
  }
}

}  // namespace ms::testing
