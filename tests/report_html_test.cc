// report.html: one file that opens offline, with every picture decoded by a
// real browser and no console message, from a run folder made here.
#include "sapmvs/report/report_html.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>
#include <regex>
#include <string>

#include "cli_test_util.h"
#include "sapmvs/util/error.h"
#include "sapmvs/util/world_file.h"
#include "test_util.h"

namespace sapmvs {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

// A run folder as `sapmvs run` leaves it: report.json (two groups, their
// ground, the run's and the matching's stages), dsm.png + .pgw, ortho.png.
fs::path MakeReportRunFolder(const std::string& name) {
  const fs::path dir = test::ScratchDir() / name;
  fs::remove_all(dir);
  fs::create_directories(dir);
  json r;
  r["report_version"] = 2;
  r["block"] = "/data/<b>&survey/block.yaml";
  r["command_line"] = {"sapmvs", "run", "/data/<b>&survey/block.yaml", "--out", "my run"};
  r["images"] = 7;
  r["points"] = 123456;
  r["total_seconds"] = 61.5;
  r["total_hms"] = "0:01:02";
  r["crs"] = {{"epsg", 32632}, {"name", "WGS 84 / UTM zone 32N"}, {"definition", "EPSG:32632"}};
  r["ortho"] = {{"cell", 0.5},         {"width", 90}, {"height", 60},
                {"filled_share", 0.7}, {"images", 7}, {"objects", 3}};
  json groups = json::array();
  for (int g = 0; g < 2; ++g) {
    const double x0 = 1000 + 50 * g;
    groups.push_back({{"group", g + 1},
                      {"images", {"a.jpg", "b.jpg", "c.jpg", "d.jpg"}},
                      {"points", 60000 + g},
                      {"seconds", 20.0 + g},
                      {"memory_estimate_bytes", {{"total", 3e8}}},
                      {"memory_measured_bytes", {{"peak_rss", 2.5e8}}},
                      {"region", {{x0, 2000}, {x0 + 50, 2000}, {x0 + 50, 2030}, {x0, 2030}}}});
  }
  r["groups"] = groups;
  r["stages"] = {{{"stage", "propagation"}, {"wall_seconds", 30.0}, {"cpu_seconds", 55.0}},
                 {{"stage", "run plan"},
                  {"wall_seconds", 2.0},
                  {"cpu_seconds", 3.0},
                  {"peak_rss_bytes", 1.2e8}},
                 {{"stage", "run match"},
                  {"wall_seconds", 41.0},
                  {"cpu_seconds", 80.0},
                  {"peak_rss_bytes", 2.5e8}}};
  r["merge"] = {{"input", 130000}, {"kept", 123456}, {"cross_group_duplicates", 6544}};
  std::ofstream(dir / "report.json") << r.dump(2);
  // The DSM picture: 100 x 30 cells of 1 unit from (1000, 2030), a legend to
  // the right, as dsm_picture.cc lays it out.
  cv::Mat dsm(30, 140, CV_8UC3, cv::Scalar(200, 120, 40));
  cv::imwrite((dir / "dsm.png").string(), dsm);
  WriteWorldFile(dir / "dsm.pgw", 1000, 2030, 1);
  cv::Mat ortho(60, 90, CV_8UC4, cv::Scalar(60, 160, 90, 255));
  cv::imwrite((dir / "ortho.png").string(), ortho);
  return dir;
}

int Occurrences(const std::string& text, const std::string& what) {
  int n = 0;
  for (size_t at = text.find(what); at != std::string::npos; at = text.find(what, at + 1)) ++n;
  return n;
}

TEST(ReportHtml, IsOneFileThatOpensOffline) {
  const fs::path dir = MakeReportRunFolder("report_offline");
  const fs::path html = WriteReportHtml(dir);
  EXPECT_EQ(html, dir / "report.html");
  const std::string page = test::Slurp(html);
  // Every picture inline, every link within the page; no style sheet or
  // script from elsewhere.
  const std::regex attribute(R"re((src|href)\s*=\s*"([^"]*)")re");
  int links = 0;
  for (auto it = std::sregex_iterator(page.begin(), page.end(), attribute);
       it != std::sregex_iterator(); ++it, ++links) {
    const std::string value = (*it)[2];
    EXPECT_TRUE(value.rfind("data:image/png;base64,", 0) == 0 || value.rfind("#", 0) == 0)
        << (*it)[1] << "=" << value.substr(0, 60);
  }
  EXPECT_GE(links, 2 + 5);
  EXPECT_EQ(Occurrences(page, "<link"), 0);
  EXPECT_EQ(Occurrences(page, "url("), 0);
  EXPECT_EQ(Occurrences(page, "<img "), 2);
  // The user's text is escaped, wherever it appears.
  EXPECT_EQ(Occurrences(page, "<b>&survey"), 0);
  EXPECT_GE(Occurrences(page, "&lt;b&gt;&amp;survey"), 2);
  EXPECT_NE(page.find("&#39;my run&#39;"),
            std::string::npos);  // the command, quoted as a shell would
  // The two groups' ground over the DSM: 50 x 30 units from x = 1000 and
  // 1050, i.e. pixels 0.5 + 0..50 and 50..100 of the picture (world file:
  // the top-left pixel's centre).
  EXPECT_EQ(Occurrences(page, "<title>group "), 2);
  EXPECT_NE(page.find("points=\"0.0,30.0 50.0,30.0 50.0,0.0 0.0,0.0"), std::string::npos);
  EXPECT_NE(page.find("points=\"50.0,30.0 100.0,30.0 100.0,0.0 50.0,0.0"), std::string::npos);
  EXPECT_NE(page.find("WGS 84 / UTM zone 32N (EPSG:32632)"), std::string::npos);
  EXPECT_NE(page.find("5.0 %"), std::string::npos);              // duplicates: 6,544 of 130,000
  EXPECT_EQ(page.find("id=\"evaluation\""), std::string::npos);  // none was made
}

TEST(ReportHtml, AddsTheEvaluationBesideIt) {
  const fs::path dir = MakeReportRunFolder("report_evaluation");
  json e;
  e["cloud"] = {{"path", (dir / "cloud.ply").string()}, {"points", 123456}};
  e["reference"] = {{"path", "/data/lidar.las"}, {"kind", "lidar"}};
  e["tolerance"] = 1;
  e["rows"] = {{{"threshold", nullptr},
                {"checkpoints", 120000},
                {"rmse", 1.61},
                {"max_abs", 53.2},
                {"mean", 0.05},
                {"median_abs", 0.02},
                {"within_tolerance", 0.936}},
               {{"threshold", 0.5},
                {"checkpoints", 110000},
                {"rmse", 0.07},
                {"max_abs", 0.49},
                {"mean", 0.004},
                {"median_abs", 0.02},
                {"within_tolerance", 1.0}}};
  std::ofstream(dir / "evaluation.json") << e.dump();
  fs::create_directories(dir / "evaluation");
  cv::imwrite((dir / "evaluation" / "dz_histogram.png").string(),
              cv::Mat(40, 60, CV_8UC3, cv::Scalar(255, 255, 255)));
  const std::string page = test::Slurp(WriteReportHtml(dir));
  EXPECT_NE(page.find("id=\"evaluation\""), std::string::npos);
  EXPECT_NE(page.find("93.6 %"), std::string::npos);
  EXPECT_NE(page.find("|dz| ≤ 0.50"), std::string::npos);
  EXPECT_EQ(Occurrences(page, "<img "), 3);
}

TEST(ReportHtml, NamesWhatIsMissing) {
  const fs::path dir = test::ScratchDir() / "report_missing";
  fs::remove_all(dir);
  fs::create_directories(dir);
  try {
    WriteReportHtml(dir);
    FAIL() << "no report.json, yet report.html was written";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find((dir / "report.json").string()), std::string::npos)
        << e.what();
  }
  std::ofstream(dir / "report.json") << "{\"points\": 3}";  // an evaluation's, say
  EXPECT_THROW(WriteReportHtml(dir), Error);
  std::ofstream(dir / "report.json") << "{not json";
  EXPECT_THROW(WriteReportHtml(dir), Error);
  EXPECT_FALSE(fs::exists(dir / "report.html"));
}

TEST(ReportHtml, TheCommandMakesItAgainOrSaysWhyNot) {
  const fs::path dir = MakeReportRunFolder("report_command");
  auto r = test::RunCli("report " + dir.string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(r.out, "wrote         " + (dir / "report.html").string() + "\n");
  EXPECT_TRUE(fs::exists(dir / "report.html"));
  fs::remove(dir / "report.json");
  r = test::RunCli("report " + dir.string());
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_EQ(r.out, "");
  EXPECT_EQ(test::CountLines(r.err), 1) << r.err;
  EXPECT_NE(r.err.find((dir / "report.json").string()), std::string::npos) << r.err;
}

// "N/M": the page's count of decoded pictures, after the load event.
std::string PicturesDecoded(const std::string& dom) {
  std::smatch m;
  const std::regex decoded(R"re(data-pictures-decoded="([0-9]+/[0-9]+)")re");
  return std::regex_search(dom, m, decoded) ? m[1].str() : "(no count: the script did not run)";
}

TEST(ReportHtml, EveryPictureDecodesInABrowser) {
  const fs::path dir = MakeReportRunFolder("report_browser");
  test::BrowserPage page = test::LoadInHeadlessBrowser(WriteReportHtml(dir));
  SAPMVS_REQUIRE_BROWSER(page);
  EXPECT_EQ(PicturesDecoded(page.dom), "2/2") << page.dom.substr(0, 2000);
  EXPECT_TRUE(page.console.empty()) << page.console.front();
  // The check sees a picture that does not decode, and the page says so.
  test::WriteFileBytes(dir / "ortho.png", "\x89PNG\r\n\x1a\n not a picture");
  page = test::LoadInHeadlessBrowser(WriteReportHtml(dir));
  EXPECT_EQ(PicturesDecoded(page.dom), "1/2");
  EXPECT_NE(page.dom.find("orthophoto: the picture could not be decoded"), std::string::npos);
  // And it hears a console message when there is one.
  test::WriteFileBytes(dir / "control.html", "<script>console.error('control')</script>");
  EXPECT_EQ(test::LoadInHeadlessBrowser(dir / "control.html").console.size(), 1u);
}

}  // namespace
}  // namespace sapmvs
