// End-to-end check of `caustica compare`'s HTML report in headless Chromium: the page's
// own #selftest mode clicks through the integrators (the shown image must change), checks the
// plot and the table, and reports in the title; the console must stay silent; a screenshot
// must not be blank.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "image/image_io.h"
#include "integrators/registry.h"

namespace fs = std::filesystem;

namespace {

std::string read_file(const fs::path& p) {
  std::ifstream f(p);
  std::stringstream ss;
  ss << f.rdbuf();
  return ss.str();
}

std::string chromium_command(const fs::path& profile) {
  return "chromium --headless --no-sandbox --disable-gpu --disable-quic --no-first-run "
         "--disable-background-networking --disable-component-update --disable-sync "
         "--user-data-dir=" +
         profile.string();
}

bool chromium_available() { return std::system("command -v chromium >/dev/null 2>&1") == 0; }

// Runs `caustica compare cornell` with the integrators into dir/report and returns the DOM of its
// index.html after the page's #selftest ran in headless Chromium.
std::string compare_and_selftest(const fs::path& dir, const std::string& integrators) {
  const std::string compare =
      std::string(CAUSTICA_BINARY) + " compare cornell --integrators " + integrators +
      " --time 1 --reference-time 1 --resolution 48x48 --reference-integrator pt --out " +
      (dir / "report").string() + " > " + (dir / "compare.log").string() + " 2>&1";
  EXPECT_EQ(std::system(compare.c_str()), 0) << read_file(dir / "compare.log");
  const std::string url = "file://" + (dir / "report" / "index.html").string();
  const std::string dump =
      chromium_command(dir / "profile") +
      " --enable-logging=stderr --v=0 --virtual-time-budget=10000 --dump-dom '" + url +
      "#selftest' > " + (dir / "dom.html").string() + " 2> " + (dir / "chromium.log").string();
  EXPECT_EQ(std::system(dump.c_str()), 0) << read_file(dir / "chromium.log");
  return read_file(dir / "dom.html");
}

}  // namespace

TEST(ReportBrowser, ViewerPlotAndTableWorkInHeadlessChromium) {
  if (!chromium_available()) {
    if (std::getenv("CI")) FAIL() << "chromium is not installed (scripts/test.sh installs it)";
    GTEST_SKIP() << "chromium is not installed; run scripts/install-deps.sh chromium";
  }
  const fs::path dir = fs::path(testing::TempDir()) / "caustica_report_test";
  fs::remove_all(dir);
  fs::create_directories(dir);
  // Two integrators if the bidirectional family is there, so switching shows different renders.
  std::string integrators = "pt";
  for (const auto& n : caustica::integrator_names())
    if (n == "bpt" || (n == "lt" && integrators == "pt")) integrators = "pt," + n;
  const std::string dom = compare_and_selftest(dir, integrators);
  for (const char* f : {"index.html", "results.json", "results.csv", "convergence.svg",
                        "reference.png", "pt.png", "pt.exr", "pt_error.png"})
    EXPECT_TRUE(fs::exists(dir / "report" / f)) << f;
  const std::string html = read_file(dir / "report" / "index.html");
  EXPECT_EQ(html.find("http://"), html.find("http://www.w3.org/2000/svg"));  // no network resources
  EXPECT_EQ(html.find("https://"), std::string::npos);

  const std::string url = "file://" + (dir / "report" / "index.html").string();
  EXPECT_NE(dom.find("<title>selftest:pass</title>"), std::string::npos)
      << dom.substr(0, std::min<size_t>(dom.size(), 400));
  // Any console message from the page (errors, uncaught exceptions) is a failure.
  const std::string log = read_file(dir / "chromium.log");
  EXPECT_EQ(log.find("CONSOLE"), std::string::npos) << log;

  const fs::path shot = dir / "shot.png";
  const std::string screenshot = chromium_command(dir / "profile") +
                                 " --window-size=1000,900 --screenshot=" + shot.string() + " '" +
                                 url + "' > /dev/null 2>&1";
  ASSERT_EQ(std::system(screenshot.c_str()), 0);
  const caustica::Image img = caustica::read_image(shot.string(), false);
  ASSERT_GT(img.pixel_count(), 0u);
  double sum = 0, sum2 = 0;
  for (size_t i = 0; i < img.pixel_count(); ++i) {
    const double v = img[i].luminance();
    sum += v;
    sum2 += v * v;
  }
  const double mean = sum / img.pixel_count();
  const double stddev = std::sqrt(std::max(0.0, sum2 / img.pixel_count() - mean * mean));
  EXPECT_GT(stddev, 0.05) << "the screenshot is blank (mean " << mean << ")";
}

// A click on the picture shows what guided-pt learned at that pixel: the page's #selftest clicks
// the middle of the picture and checks the caption names that pixel and the view was drawn.
TEST(ReportBrowser, AClickShowsWhatGuidingLearnedAtThatPixel) {
  if (!chromium_available()) {
    if (std::getenv("CI")) FAIL() << "chromium is not installed (scripts/test.sh installs it)";
    GTEST_SKIP() << "chromium is not installed; run scripts/install-deps.sh chromium";
  }
  const auto names = caustica::integrator_names();
  if (std::find(names.begin(), names.end(), "guided-pt") == names.end()) GTEST_SKIP();
  const fs::path dir = fs::path(testing::TempDir()) / "caustica_report_click_test";
  fs::remove_all(dir);
  fs::create_directories(dir);
  const std::string dom = compare_and_selftest(dir, "pt,guided-pt");
  EXPECT_NE(dom.find("<title>selftest:pass</title>"), std::string::npos);
  const size_t at = dom.find("<div id=\"guideselftest\" class=\"hint\">");
  ASSERT_NE(at, std::string::npos);
  EXPECT_EQ(dom.substr(at, 80).find("guideselftest:pass"), 37u) << dom.substr(at, 200);
  const std::string log = read_file(dir / "chromium.log");
  EXPECT_EQ(log.find("CONSOLE"), std::string::npos) << log;
}
