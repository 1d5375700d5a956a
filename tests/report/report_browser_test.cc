// The session report in a real browser: a small simulated session (config/scenarios/small.yaml,
// about 5 s) is calibrated and reported with the `selfcal` command line, then Debian's chromium
// opens the file headless, offline, with a fresh profile. The page must load without a console
// message of its own, run its script to the end, draw both 3D views (the screenshot's pixels
// inside each canvas are not blank, and the two differ), and show the result file's numbers.
#include <gtest/gtest.h>
#include <unistd.h>
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <regex>
#include <sstream>
#include <string>

#include "tests/report/png_pixels.h"

namespace selfcal {
namespace {

std::string Slurp(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

int Shell(const std::string& command) { return std::system(command.c_str()); }

// The browser as the tests start it: headless, no GPU (software WebGL, SwiftShader, which
// Chromium wants named since it stopped falling back to it silently), nothing from the network,
// a fresh profile, console messages on stderr.
std::string Chromium(const std::string& folder, const std::string& profile) {
  return "chromium --headless --no-sandbox --disable-gpu --enable-unsafe-swiftshader "
         "--disable-quic --no-first-run --disable-background-networking "
         "--disable-component-update --disable-sync --user-data-dir=" +
         folder + "/" + profile + " --enable-logging=stderr --v=0 --window-size=1300,3400 " +
         "--virtual-time-budget=3000 ";
}

class ReportInBrowser : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    folder_ = ::testing::TempDir() + "report_browser_" + std::to_string(getpid());
    std::filesystem::create_directories(folder_);
    const std::string source = std::getenv("SELFCAL_SOURCE_DIR");
    const std::string selfcal = SELFCAL_BINARY;
    const std::string sensor = source + "/config/sensors/kinect_azure_nfov_binned.yaml";
    ASSERT_EQ(
        Shell(selfcal + " -q simulate " + source + "/config/scenarios/small.yaml --threads 2 " +
              "--out " + folder_ + "/sim > /dev/null"),
        0);
    const std::string log = folder_ + "/sim/recording.lcmlog";
    Shell(selfcal + " -q calibrate --robot " + folder_ + "/sim/nominal.yaml --sensor " + sensor +
          " --log " + log + " --out " + folder_ + "/result.yaml --threads 2 > " + folder_ +
          "/calibrate.txt");
    ASSERT_EQ(Shell(selfcal + " -q report " + folder_ + "/result.yaml --log " + log + " --out " +
                    folder_ + "/report.html"),
              0);
    const std::string url = "file://" + folder_ + "/report.html";
    ASSERT_EQ(Shell(Chromium(folder_, "dom") + "--dump-dom " + url + " > " + folder_ +
                    "/dom.html 2> " + folder_ + "/dom.log"),
              0);
    ASSERT_EQ(Shell(Chromium(folder_, "shot") + "--screenshot=" + folder_ + "/shot.png " + url +
                    " > /dev/null 2> " + folder_ + "/shot.log"),
              0);
    dom_ = Slurp(folder_ + "/dom.html");
  }
  static void TearDownTestSuite() { std::filesystem::remove_all(folder_); }

  static std::string folder_, dom_;
};
std::string ReportInBrowser::folder_, ReportInBrowser::dom_;

TEST_F(ReportInBrowser, LoadsWithoutConsoleMessagesAndRunsItsScriptToTheEnd) {
  for (const char* log : {"/dom.log", "/shot.log"}) {
    std::istringstream lines(Slurp(folder_ + log));
    for (std::string line; std::getline(lines, line);) {
      if (line.find(":CONSOLE") == std::string::npos) continue;
      // SwiftShader's note when the screenshot reads the canvas back: the browser's, not the
      // page's.
      if (line.find("GL Driver Message (OpenGL, Performance") != std::string::npos) continue;
      ADD_FAILURE() << log << ": " << line;
    }
  }
  EXPECT_NE(dom_.find("data-ready=\"yes\""), std::string::npos);
}

TEST_F(ReportInBrowser, IsOneFileUnder20MbThatNeedsNoNetwork) {
  const std::string page = Slurp(folder_ + "/report.html");
  EXPECT_LT(page.size(), 20u << 20);
  EXPECT_EQ(page.find("src=\"http"), std::string::npos);
  EXPECT_EQ(page.find("href=\"http"), std::string::npos);
  EXPECT_EQ(page.find("<link"), std::string::npos);
  EXPECT_NE(page.find("REVISION=\"111\""), std::string::npos);  // three.js, inlined
  EXPECT_NE(page.find("Chart.js v3"), std::string::npos);
  EXPECT_NE(page.find("<summary>libjs-three</summary>"), std::string::npos);  // its licence
}

TEST_F(ReportInBrowser, BothViewsDrawTheCloudsAndTheyDiffer) {
  std::smatch counts;
  ASSERT_TRUE(std::regex_search(dom_, counts, std::regex("data-rendered=\"(\\d+),(\\d+)\"")));
  EXPECT_GT(std::stoi(counts[1]), 1000);
  const auto image = testing::ReadPng(folder_ + "/shot.png");
  ASSERT_TRUE(image);
  std::vector<std::vector<std::uint8_t>> views;
  for (const char* which : {"before", "after"}) {
    std::smatch rect;
    ASSERT_TRUE(std::regex_search(
        dom_, rect,
        std::regex(std::string("data-view-") + which + "=\"(\\d+),(\\d+),(\\d+),(\\d+)\"")));
    const auto x0 = std::stoul(rect[1]) + 3, y0 = std::stoul(rect[2]) + 3;
    const auto x1 = x0 + std::stoul(rect[3]) - 6, y1 = y0 + std::stoul(rect[4]) - 6;
    ASSERT_LE(y1, image->height) << "the view is below the screenshot";
    std::size_t drawn = 0, area = 0;
    std::vector<std::uint8_t> pixels;
    for (auto y = y0; y < y1; ++y) {
      for (auto x = x0; x < x1; ++x, ++area) {
        const std::uint8_t* p =
            image->At(static_cast<std::uint32_t>(x), static_cast<std::uint32_t>(y));
        drawn += p[0] < 230 || p[1] < 230 || p[2] < 230 ? 1 : 0;
        pixels.insert(pixels.end(), p, p + 3);
      }
    }
    EXPECT_GT(drawn, area / 50) << which << ": " << drawn << " of " << area << " pixels drawn";
    views.push_back(std::move(pixels));
  }
  EXPECT_NE(views[0], views[1]) << "the old and the new model fuse the scans alike";
}

// The value at a dotted path of the result's calibration section ("parameters.3.calibrated_rad").
double ResultValue(const YAML::Node& calibration, const std::string& key) {
  YAML::Node node = YAML::Clone(calibration);
  std::stringstream parts(key);
  for (std::string part; std::getline(parts, part, '.');) {
    node = node.IsSequence() ? node[std::stoul(part)] : node[part];
  }
  return node.as<double>();
}

// A number the page shows with its result-file key: as shown, and the file's value so scaled.
struct ShownNumber {
  std::string text;
  double shown = 0, expected = 0, half_digit = 0;
  bool Matches() const {
    return std::abs(shown - expected) <= half_digit * (1 + 1e-9) + 1e-12 * std::abs(expected);
  }
};

std::map<std::string, ShownNumber> ShownNumbers(const std::string& dom, const YAML::Node& result) {
  const std::regex number(
      "data-key=\"([^\"]+)\" data-scale=\"([^\"]+)\" data-decimals=\"(\\d+)\">([^<]+)<");
  std::map<std::string, ShownNumber> numbers;
  for (auto it = std::sregex_iterator(dom.begin(), dom.end(), number); it != std::sregex_iterator();
       ++it) {
    ShownNumber& entry = numbers[(*it)[1]];
    entry.text = (*it)[4];
    entry.shown = std::stod((*it)[4]);
    entry.expected = ResultValue(result, (*it)[1]) * std::stod((*it)[2]);
    entry.half_digit = 0.5 * std::pow(10.0, -std::stoi((*it)[3]));
  }
  return numbers;
}

TEST_F(ReportInBrowser, ShowsTheResultFilesNumbers) {
  const YAML::Node result = YAML::LoadFile(folder_ + "/result.yaml")["calibration"];
  const auto numbers = ShownNumbers(dom_, result);
  const std::size_t checked = numbers.size();
  for (const auto& [key, number] : numbers) {
    EXPECT_TRUE(number.Matches()) << key << ": page " << number.text << ", file "
                                  << number.expected;
  }
  const std::size_t parameters = result["parameters"].size(),
                    iterations = result["per_iteration"].size();
  std::printf("numbers checked: %zu (%zu parameters, %zu iterations)\n", checked, parameters,
              iterations);
  EXPECT_GT(parameters, 20u);
  // The summary's 9, three per parameter (one fewer per infinite std_dev), seven per iteration.
  EXPECT_GE(checked, 9 + 2 * parameters + 7 * iterations);
  // The gate's decision is what `selfcal calibrate` printed as usable.
  const std::string printed = Slurp(folder_ + "/calibrate.txt");
  std::smatch usable;
  ASSERT_TRUE(
      std::regex_search(printed, usable, std::regex("usable: (yes|no) \\((.*)\\), written")));
  EXPECT_NE(dom_.find(usable[1] == "yes" ? "<b>ACCEPTED</b>" : "<b>REFUSED</b>"),
            std::string::npos);
  std::string reason;  // as HTML text
  for (char c : usable[2].str()) reason += c == '>' ? std::string("&gt;") : std::string(1, c);
  EXPECT_NE(dom_.find(reason), std::string::npos) << reason;
}

// "What changed": the summary, every finding's numbers in its unit with the standard deviation,
// one row per finding, and what keeping the old model would cost, as the result file has them.
TEST_F(ReportInBrowser, ShowsWhatChangedWithTheResultFilesNumbers) {
  const YAML::Node result = YAML::LoadFile(folder_ + "/result.yaml")["calibration"];
  const YAML::Node change = result["change"];
  ASSERT_TRUE(change.IsMap());
  EXPECT_NE(dom_.find("<p id=\"change-summary\"><b>" + change["summary"].as<std::string>()),
            std::string::npos)
      << change["summary"];
  const auto numbers = ShownNumbers(dom_, result);
  const auto expect_shown = [&](const std::string& key) {
    const auto number = numbers.find(key);
    ASSERT_NE(number, numbers.end()) << key << " is not on the page";
    EXPECT_TRUE(number->second.Matches())
        << key << ": page " << number->second.text << ", file " << number->second.expected;
  };
  const YAML::Node findings = change["findings"];
  ASSERT_GT(findings.size(), 0u) << "small.yaml's nominal model is far from its truth";
  std::size_t values = 0;
  for (std::size_t i = 0; i < findings.size(); ++i) {
    for (const auto& entry : findings[i]) {
      const std::string key = entry.first.as<std::string>();
      if (key == "kind" || key == "joint" || key == "text") continue;
      ASSERT_TRUE(entry.second.IsScalar()) << key << " is null: the calibration has a covariance";
      expect_shown("change.findings." + std::to_string(i) + "." + key);
      ++values;
    }
    EXPECT_NE(dom_.find(findings[i]["text"].as<std::string>()), std::string::npos);
  }
  EXPECT_GE(values, 2 * findings.size());  // each a value and its deviation
  const auto table = dom_.find("<table id=\"change-findings\">");
  ASSERT_NE(table, std::string::npos);
  const std::string rows = dom_.substr(table, dom_.find("</table>", table) - table);
  std::size_t count = 0;
  for (auto at = rows.find("<tr><td>"); at != std::string::npos; at = rows.find("<tr><td>", at + 1))
    ++count;
  EXPECT_EQ(count, findings.size());
  for (const char* where : {"sensor", "flange"}) {
    for (const char* what : {"rms_position_m", "max_position_m"}) {
      expect_shown(std::string("change.keeping_the_start_model.") + where + "." + what);
    }
  }
}

// The predicted error map is plotted: one point per bin with configurations, and the data drawn
// in colour inside its canvas.
TEST_F(ReportInBrowser, PlotsThePredictedErrorMap) {
  const YAML::Node map =
      YAML::LoadFile(folder_ + "/result.yaml")["calibration"]["predicted_error"]["map"];
  ASSERT_GT(map.size(), 0u);
  std::size_t bins = 0;
  for (const auto& joint : map) {
    for (const auto& samples : joint["samples"]) bins += samples.as<std::size_t>() > 0 ? 1 : 0;
  }
  std::smatch points, rect;
  ASSERT_TRUE(std::regex_search(dom_, points, std::regex("data-error-map=\"(\\d+)\"")));
  EXPECT_EQ(std::stoul(points[1]), bins);
  ASSERT_TRUE(std::regex_search(dom_, rect,
                                std::regex("data-plot-error-map=\"(\\d+),(\\d+),(\\d+),(\\d+)\"")));
  const auto image = testing::ReadPng(folder_ + "/shot.png");
  ASSERT_TRUE(image);
  const auto x0 = std::stoul(rect[1]), y0 = std::stoul(rect[2]);
  const auto x1 = x0 + std::stoul(rect[3]), y1 = y0 + std::stoul(rect[4]);
  ASSERT_LE(y1, image->height) << "the plot is below the screenshot";
  // Coloured pixels: the joints' lines and points, not the grey axes, grid and text.
  std::size_t coloured = 0;
  for (auto y = y0; y < y1; ++y) {
    for (auto x = x0; x < x1; ++x) {
      const std::uint8_t* p =
          image->At(static_cast<std::uint32_t>(x), static_cast<std::uint32_t>(y));
      coloured += std::max({p[0], p[1], p[2]}) - std::min({p[0], p[1], p[2]}) > 80 ? 1 : 0;
    }
  }
  EXPECT_GT(coloured, 500u) << coloured << " coloured pixels in the plot";
}

TEST_F(ReportInBrowser, ItsResidualsAreTheValidationRmsOfTheResult) {
  const YAML::Node validation =
      YAML::LoadFile(folder_ + "/result.yaml")["calibration"]["validation"];
  const auto histogram = dom_.find("\"histogram\": {");
  ASSERT_NE(histogram, std::string::npos);
  const std::string block = dom_.substr(histogram, dom_.find('}', histogram) - histogram);
  for (const char* which : {"before", "after"}) {
    std::smatch rms, matches;
    ASSERT_TRUE(std::regex_search(block, rms,
                                  std::regex(std::string("\"rms_") + which + "_m\": ([0-9.e-]+)")));
    ASSERT_TRUE(std::regex_search(block, matches,
                                  std::regex(std::string("\"matches_") + which + "\": (\\d+)")));
    const double expected = validation[std::string("rms_") + which + "_m"].as<double>();
    EXPECT_NEAR(std::stod(rms[1]), expected, 1e-3 * expected) << which;
    EXPECT_EQ(std::stoul(matches[1]),
              validation[std::string("matches_") + which].as<std::size_t>());
  }
}

}  // namespace
}  // namespace selfcal
