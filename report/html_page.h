// Pieces of the run report's self-contained HTML: escaping, tables and images embedded as
// data URIs (the page needs no other file and no network).
#pragma once

#include <opencv2/core.hpp>
#include <string>
#include <vector>

namespace ms {

// Text made safe inside HTML/SVG elements and attribute values.
std::string EscapeHtml(const std::string& text);

std::string Base64Encode(const std::string& bytes);

// <img> of `image` (BGR) encoded as PNG in a data URI; `alt` is escaped.
std::string PngImageTag(const cv::Mat& image, const std::string& alt);

// A table with a header row; cells are escaped unless the row is added with AddRawRow.
class HtmlTable {
 public:
  explicit HtmlTable(std::vector<std::string> header, std::string css_class = "");
  void AddRow(const std::vector<std::string>& cells);
  void AddRawRow(const std::vector<std::string>& cells);  // cells already HTML
  std::string Html() const;

 private:
  std::string css_class_;
  std::string head_;
  std::string body_;
};

}  // namespace ms
