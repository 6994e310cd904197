// Line-oriented text parsing with errors that name "<file>:<line>: <field>: <problem>".
#pragma once

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

namespace ms {

class TextReader {
 public:
  // Reads the file into memory (bounded by max_bytes, see ReadFileToString).
  explicit TextReader(const std::string& path, uint64_t max_bytes = uint64_t{1} << 31);
  // Parses an in-memory buffer; `name` is used in error messages.
  TextReader(std::string name, std::string contents);

  // Next line (without the newline, '\r' stripped). False at end of input.
  bool NextLine(std::string_view* line);
  // Next line that is neither empty/whitespace nor starts with `comment` (if non-zero).
  bool NextDataLine(std::string_view* line, char comment = '#');
  // Like NextDataLine but throws InputError("unexpected end of file, expected <what>").
  std::string_view RequireDataLine(const std::string& what, char comment = '#');

  // Whitespace-separated tokens of the rest of the file, one at a time (line-agnostic, as in
  // NVM and Bundler). Throws on end of file naming `what`.
  std::string_view NextToken(const std::string& what);
  bool AtEnd();  // True if only whitespace remains.

  int line_number() const { return line_number_; }
  const std::string& name() const { return name_; }

  // "<file>:<line>: <message>"
  [[noreturn]] void Fail(const std::string& message) const;

  // Token parsing. `field` names the value in errors. Finite doubles only unless allow_nonfinite.
  double ParseDouble(std::string_view token, const std::string& field,
                     bool allow_nonfinite = false) const;
  int64_t ParseInt(std::string_view token, const std::string& field, int64_t min = INT64_MIN,
                   int64_t max = INT64_MAX) const;

  double NextDouble(const std::string& field) { return ParseDouble(NextToken(field), field); }
  int64_t NextInt(const std::string& field, int64_t min = INT64_MIN, int64_t max = INT64_MAX) {
    return ParseInt(NextToken(field), field, min, max);
  }

 private:
  std::string name_;
  std::string data_;
  size_t pos_ = 0;
  int line_number_ = 0;  // line of the last line or token returned (1-based)
  int newlines_ = 0;     // '\n' characters before pos_
};

// Splits on spaces/tabs, skipping empty tokens.
std::vector<std::string_view> SplitFields(std::string_view line);
std::string_view Trim(std::string_view s);

}  // namespace ms
