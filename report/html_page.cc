#include "report/html_page.h"

#include <opencv2/imgcodecs.hpp>

#include "base/error.h"

namespace ms {

std::string EscapeHtml(const std::string& text) {
  std::string out;
  out.reserve(text.size());
  for (const char c : text) {
    switch (c) {
      case '&':
        out += "&amp;";
        break;
      case '<':
        out += "&lt;";
        break;
      case '>':
        out += "&gt;";
        break;
      case '"':
        out += "&quot;";
        break;
      case '\'':
        out += "&#39;";
        break;
      default:
        out += c;
    }
  }
  return out;
}

std::string Base64Encode(const std::string& bytes) {
  static constexpr char kAlphabet[] =
      "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  out.reserve((bytes.size() + 2) / 3 * 4);
  size_t i = 0;
  for (; i + 2 < bytes.size(); i += 3) {
    const uint32_t v = (uint32_t{static_cast<uint8_t>(bytes[i])} << 16) |
                       (uint32_t{static_cast<uint8_t>(bytes[i + 1])} << 8) |
                       uint32_t{static_cast<uint8_t>(bytes[i + 2])};
    for (const int shift : {18, 12, 6, 0}) out += kAlphabet[(v >> shift) & 63];
  }
  if (i < bytes.size()) {
    const bool two = i + 1 < bytes.size();
    const uint32_t v = (uint32_t{static_cast<uint8_t>(bytes[i])} << 16) |
                       (two ? uint32_t{static_cast<uint8_t>(bytes[i + 1])} << 8 : 0u);
    out += kAlphabet[(v >> 18) & 63];
    out += kAlphabet[(v >> 12) & 63];
    out += two ? kAlphabet[(v >> 6) & 63] : '=';
    out += '=';
  }
  return out;
}

std::string PngImageTag(const cv::Mat& image, const std::string& alt) {
  std::vector<uchar> png;
  if (image.empty() || !cv::imencode(".png", image, png)) {
    throw InternalError("PNG encoding failed for the picture '" + alt + "'");
  }
  return "<img alt=\"" + EscapeHtml(alt) + "\" width=\"" + std::to_string(image.cols) +
         "\" height=\"" + std::to_string(image.rows) + "\" src=\"data:image/png;base64," +
         Base64Encode(std::string(png.begin(), png.end())) + "\">";
}

HtmlTable::HtmlTable(std::vector<std::string> header, std::string css_class)
    : css_class_(std::move(css_class)) {
  head_ = "<tr>";
  for (const std::string& cell : header) head_ += "<th>" + EscapeHtml(cell) + "</th>";
  head_ += "</tr>\n";
}

void HtmlTable::AddRow(const std::vector<std::string>& cells) {
  std::vector<std::string> escaped;
  for (const std::string& cell : cells) escaped.push_back(EscapeHtml(cell));
  AddRawRow(escaped);
}

void HtmlTable::AddRawRow(const std::vector<std::string>& cells) {
  body_ += "<tr>";
  for (const std::string& cell : cells) body_ += "<td>" + cell + "</td>";
  body_ += "</tr>\n";
}

std::string HtmlTable::Html() const {
  return "<table" + (css_class_.empty() ? std::string() : " class=\"" + css_class_ + "\"") +
         ">\n<thead>" + head_ + "</thead>\n<tbody>\n" + body_ + "</tbody>\n</table>\n";
}

}  // namespace ms
