#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>

#include "base/error.h"
#include "report/html_page.h"
#include "report/run_folder.h"
#include "report/svg_chart.h"

namespace ms {
namespace {

namespace fs = std::filesystem;

TEST(HtmlPage, Base64MatchesTheStandardVectors) {
  // RFC 4648, section 10.
  EXPECT_EQ(Base64Encode(""), "");
  EXPECT_EQ(Base64Encode("f"), "Zg==");
  EXPECT_EQ(Base64Encode("fo"), "Zm8=");
  EXPECT_EQ(Base64Encode("foo"), "Zm9v");
  EXPECT_EQ(Base64Encode("foob"), "Zm9vYg==");
  EXPECT_EQ(Base64Encode("fooba"), "Zm9vYmE=");
  EXPECT_EQ(Base64Encode("foobar"), "Zm9vYmFy");
  EXPECT_EQ(Base64Encode(std::string("\xff\x00\x80", 3)), "/wCA");
}

TEST(HtmlPage, EscapesMarkupInTextAndTables) {
  EXPECT_EQ(EscapeHtml("<a href=\"x\">&'</a>"), "&lt;a href=&quot;x&quot;&gt;&amp;&#39;&lt;/a&gt;");
  HtmlTable table({"name", "<b>"});
  table.AddRow({"<script>", "1 & 2"});
  const std::string html = table.Html();
  EXPECT_EQ(html.find("<script>"), std::string::npos);
  EXPECT_NE(html.find("&lt;script&gt;"), std::string::npos);
  EXPECT_NE(html.find("<th>&lt;b&gt;</th>"), std::string::npos);
}

TEST(HtmlPage, EmbedsAPngThatDecodes) {
  cv::Mat image(4, 6, CV_8UC3, cv::Scalar(10, 20, 30));
  const std::string tag = PngImageTag(image, "a <test>");
  EXPECT_NE(tag.find("src=\"data:image/png;base64,iVBORw0KGgo"), std::string::npos);  // PNG magic
  EXPECT_NE(tag.find("width=\"6\" height=\"4\""), std::string::npos);
  EXPECT_NE(tag.find("alt=\"a &lt;test&gt;\""), std::string::npos);
}

TEST(SvgChart, DrawsEverySeriesWithEscapedLabels) {
  LineChart chart{"points <per> iteration", "iteration", "points", {1, 2, 3, 4}, {}};
  chart.series = {{"found", {10, 20, 30, 40}}, {"inserted & kept", {5, std::nan(""), 7, 8}}};
  const std::string svg = SvgLineChart(chart);
  EXPECT_EQ(svg.rfind("<svg", 0), 0u);
  EXPECT_NE(svg.find("points &lt;per&gt; iteration"), std::string::npos);
  EXPECT_NE(svg.find("inserted &amp; kept"), std::string::npos);
  // The gap at the NaN splits the second series in two polylines: three in all.
  size_t polylines = 0;
  for (size_t at = svg.find("<polyline"); at != std::string::npos;
       at = svg.find("<polyline", at + 1)) {
    ++polylines;
  }
  EXPECT_EQ(polylines, 3u);
  EXPECT_EQ(svg.find("nan"), std::string::npos);
  EXPECT_EQ(svg.find("inf"), std::string::npos);
}

TEST(SvgChart, SaysWhenThereIsNoData) {
  LineChart chart{"empty", "x", "y", {}, {}};
  EXPECT_NE(SvgLineChart(chart).find("no data"), std::string::npos);
  chart.xs = {1, 2};
  chart.series = {{"all NaN", {std::nan(""), std::nan("")}}};
  EXPECT_NE(SvgLineChart(chart).find("no data"), std::string::npos);
}

TEST(RunFolder, SpreadsTheViewsFromTheFirstOne) {
  EXPECT_EQ(SpreadViews(12, 3, 0), (std::vector<int>{0, 4, 8}));
  EXPECT_EQ(SpreadViews(12, 3, 5), (std::vector<int>{5, 9, 1}));
  EXPECT_EQ(SpreadViews(2, 3, 0), (std::vector<int>{0, 1}));
  EXPECT_TRUE(SpreadViews(5, 0, 0).empty());
  EXPECT_TRUE(SpreadViews(0, 3, 0).empty());
}

std::string ErrorOf(const std::string& dir) {
  try {
    ReadRunFolder(dir);
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

TEST(RunFolder, BadFoldersEndWithOneLineNamingTheFile) {
  const fs::path dir = fs::temp_directory_path() / ("ms_report_test_" + std::to_string(getpid()));
  fs::remove_all(dir);
  EXPECT_NE(ErrorOf(dir.string()).find(dir.string()), std::string::npos);  // no folder
  fs::create_directories(dir);
  EXPECT_NE(ErrorOf(dir.string()).find("summary.json"), std::string::npos);
  std::ofstream(dir / "summary.json") << "{\"status\": \"finished\", ";
  EXPECT_NE(ErrorOf(dir.string()).find("summary.json: not valid JSON"), std::string::npos);
  std::ofstream(dir / "summary.json") << R"({"status": "finished", "input": 3, "iterations": []})";
  EXPECT_NE(ErrorOf(dir.string()).find("field 'input'"), std::string::npos);
  std::ofstream(dir / "summary.json")
      << R"({"status": "finished", "input": "x", "iterations": [{"iteration": "one"}]})";
  EXPECT_NE(ErrorOf(dir.string()).find("field 'iterations[]'"), std::string::npos);
  std::ofstream(dir / "summary.json")
      << R"({"status": "finished", "input": "x", "iterations": []})";
  EXPECT_NE(ErrorOf(dir.string()).find("run.h5"), std::string::npos);
  std::ofstream(dir / "run.h5") << "not hdf5";
  EXPECT_NE(ErrorOf(dir.string()).find("run.h5"), std::string::npos);
  fs::remove_all(dir);
}

}  // namespace
}  // namespace ms
