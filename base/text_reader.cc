#include "base/text_reader.h"

#include <cerrno>
#include <cmath>
#include <cstdlib>

#include "base/error.h"
#include "base/file_util.h"

namespace ms {
namespace {
bool IsSpace(char c) {
  return c == ' ' || c == '\t' || c == '\r' || c == '\n' || c == '\v' || c == '\f';
}
}  // namespace

std::string_view Trim(std::string_view s) {
  while (!s.empty() && IsSpace(s.front())) s.remove_prefix(1);
  while (!s.empty() && IsSpace(s.back())) s.remove_suffix(1);
  return s;
}

std::vector<std::string_view> SplitFields(std::string_view line) {
  std::vector<std::string_view> fields;
  size_t i = 0;
  while (i < line.size()) {
    while (i < line.size() && IsSpace(line[i])) ++i;
    size_t j = i;
    while (j < line.size() && !IsSpace(line[j])) ++j;
    if (j > i) fields.push_back(line.substr(i, j - i));
    i = j;
  }
  return fields;
}

TextReader::TextReader(const std::string& path, uint64_t max_bytes)
    : name_(path), data_(ReadFileToString(path, max_bytes)) {}

TextReader::TextReader(std::string name, std::string contents)
    : name_(std::move(name)), data_(std::move(contents)) {}

bool TextReader::NextLine(std::string_view* line) {
  if (pos_ >= data_.size()) return false;
  size_t end = data_.find('\n', pos_);
  if (end == std::string::npos) end = data_.size();
  std::string_view view(data_.data() + pos_, end - pos_);
  if (!view.empty() && view.back() == '\r') view.remove_suffix(1);
  line_number_ = newlines_ + 1;
  if (end < data_.size()) ++newlines_;
  pos_ = end + 1;
  *line = view;
  return true;
}

bool TextReader::NextDataLine(std::string_view* line, char comment) {
  std::string_view candidate;
  while (NextLine(&candidate)) {
    std::string_view trimmed = Trim(candidate);
    if (trimmed.empty()) continue;
    if (comment != 0 && trimmed.front() == comment) continue;
    *line = candidate;
    return true;
  }
  return false;
}

std::string_view TextReader::RequireDataLine(const std::string& what, char comment) {
  std::string_view line;
  if (!NextDataLine(&line, comment)) Fail("unexpected end of file, expected " + what);
  return line;
}

std::string_view TextReader::NextToken(const std::string& what) {
  while (pos_ < data_.size() && IsSpace(data_[pos_])) {
    if (data_[pos_] == '\n') ++newlines_;
    ++pos_;
  }
  if (pos_ >= data_.size()) {
    line_number_ = std::max(newlines_, 1);  // the last line
    Fail("unexpected end of file, expected " + what);
  }
  line_number_ = newlines_ + 1;  // the token's own line
  size_t start = pos_;
  while (pos_ < data_.size() && !IsSpace(data_[pos_])) ++pos_;
  return std::string_view(data_.data() + start, pos_ - start);
}

bool TextReader::AtEnd() {
  while (pos_ < data_.size() && IsSpace(data_[pos_])) {
    if (data_[pos_] == '\n') ++newlines_;
    ++pos_;
  }
  if (pos_ >= data_.size()) return true;
  line_number_ = newlines_ + 1;  // where the next token starts, for a caller's Fail()
  return false;
}

void TextReader::Fail(const std::string& message) const {
  // Line numbers count from 1; a reader that consumed tokens reports the line it stopped on.
  throw InputError(name_ + ":" + std::to_string(std::max(line_number_, 1)) + ": " + message);
}

double TextReader::ParseDouble(std::string_view token, const std::string& field,
                               bool allow_nonfinite) const {
  std::string text(token);
  char* end = nullptr;
  errno = 0;
  const double value = std::strtod(text.c_str(), &end);
  if (text.empty() || end != text.c_str() + text.size()) {
    Fail(field + ": '" + text + "' is not a number");
  }
  if (!allow_nonfinite && !std::isfinite(value))
    Fail(field + ": value '" + text + "' is not finite");
  return value;
}

int64_t TextReader::ParseInt(std::string_view token, const std::string& field, int64_t min,
                             int64_t max) const {
  std::string text(token);
  char* end = nullptr;
  errno = 0;
  const long long value = std::strtoll(text.c_str(), &end, 10);
  if (text.empty() || end != text.c_str() + text.size()) {
    Fail(field + ": '" + text + "' is not an integer");
  }
  if (errno == ERANGE || value < min || value > max) {
    Fail(field + ": " + text + " is out of range [" + std::to_string(min) + ", " +
         std::to_string(max) + "]");
  }
  return value;
}

}  // namespace ms
