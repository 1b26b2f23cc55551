// The report of a diagnosis that learned an empirical term: a labelled subsection (never a
// named cause) with the term's components, its held-out gain, the ranges it was learned on and
// its curve over the covariate with a 95 % band; the verdict's CSS class stays a class.
#include <gtest/gtest.h>

#include <regex>
#include <string>

#include "lmcal/calibrate/calibration.hpp"
#include "lmcal/report/html_report.hpp"
#include "lmcal/rig/virtual_rig.hpp"
#include "report/sections.hpp"
#include "support/temp_folder.hpp"

namespace lmcal {
namespace {

// The text of `html` from the first `from` to the next `to` after it ("" when `from` is absent).
std::string between(const std::string& html, const std::string& from, const std::string& to) {
  const auto at = html.find(from);
  if (at == std::string::npos) return "";
  return html.substr(at, html.find(to, at + from.size()) - at);
}

class ReportEmpiricalTest : public test::TempFolderTest {};

TEST(ReportEmpirical, AVerdictsClassesAreItsWordsWithTheEmpiricalTermAClassOfItsOwn) {
  EXPECT_EQ(report::verdict_class("unexplained — empirical term found"), "unexplained empirical-term-found");
  EXPECT_EQ(report::verdict_class("partly explained — empirical term found"), "partly-explained empirical-term-found");
  EXPECT_EQ(report::verdict_class("no significant discrepancy"), "no-significant-discrepancy");
  EXPECT_EQ(report::verdict_class("Explained"), "explained");
  EXPECT_EQ(report::verdict_class(" odd  \"<x>\" — "), "odd-x");
}

// Running-in hidden in a friction log (not a mechanism of the library): the diagnosis learns
// a term and the report shows it as such, with its curve and band; the calibrated model says
// it includes it.
TEST_F(ReportEmpiricalTest, ALearnedTermGetsItsLabelledSubsectionWithItsCurveAndBand) {
  FrictionRigConfig config;
  config.guides = {"SRN 35C"};
  config.runs = 6;
  RigEffects effects;
  effects.hidden.running_in = 0.1;
  effects.hidden.running_in_scale_m = 150;
  write("friction.csv", friction_log_csv(generate_friction_log(config, effects).log));
  const Calibration c = calibrate(find_calibration_set(dir_), {});
  ASSERT_TRUE(c.friction_diagnosis);
  const EmpiricalFinding& e = c.friction_diagnosis->empirical;
  ASSERT_TRUE(e.found) << c.friction_diagnosis->summary;
  const std::string html = calibration_report_html(c);

  const std::string verdict = between(html, "<p class=\"verdict ", "\">");
  EXPECT_TRUE(std::regex_match(verdict, std::regex("<p class=\"verdict [a-z0-9- ]+"))) << verdict;
  EXPECT_NE(verdict.find("empirical-term-found"), std::string::npos) << verdict;

  const std::string section = between(html, "<div class=\"empirical\">", "</div>\n");
  ASSERT_FALSE(section.empty()) << "no empirical subsection";
  EXPECT_NE(section.find("<h4 id=\"friction-empirical\">Beyond the library: an empirical term</h4>"), std::string::npos);
  EXPECT_NE(section.find("Learned from the residuals; not a named cause."), std::string::npos);
  EXPECT_NE(section.find(report::escape_xml(e.formula)), std::string::npos) << "no formula";
  for (const auto& component : e.components) {
    const std::string row = between(section, "<tr><td>" + report::escape_xml(component.symbol) + "</td>", "</tr>");
    ASSERT_FALSE(row.empty()) << component.symbol << " has no row";
    EXPECT_NE(row.find(report::interval(component.coefficient)), std::string::npos) << row;
    if (component.has_scale) {
      EXPECT_NE(row.find(report::interval(component.scale)), std::string::npos) << row;
    }
  }
  EXPECT_NE(section.find("RMSE " + report::num(e.cv_rmse_before) + " N before the term, " + report::num(e.cv_rmse_after) +
                         " N with it"),
            std::string::npos);
  EXPECT_NE(section.find("It resembles running-in"), std::string::npos);
  EXPECT_NE(section.find("Beyond these ranges the term is an extrapolation"), std::string::npos);
  EXPECT_EQ(section.find("accepted"), std::string::npos) << "presented as a named cause";

  // One figure: the residuals before and after as points, the term as a line with its band.
  const std::string svg = between(section, "data-plot=\"friction-empirical-term\"", "</svg>");
  ASSERT_FALSE(svg.empty()) << "no figure";
  EXPECT_NE(svg.find("<path class=\"band\" data-label=\"term (95 % band)\""), std::string::npos);
  for (const char* label : {"residual without the term", "residual with it", "term (95 % band)"})
    EXPECT_NE(svg.find(std::string("<g class=\"series\" data-label=\"") + label + "\""), std::string::npos) << label;
  const auto plots = calibration_report_plots(c);
  EXPECT_NE(std::find(plots.begin(), plots.end(), "friction-empirical-term"), plots.end());

  // The calibrated model, when it carries the term, says so.
  ASSERT_TRUE(c.calibrated.friction);
  if (!c.calibrated.friction->terms.empty()) {
    const std::string calibrated = between(html, "<h2 id=\"calibrated\">", "</section>");
    EXPECT_NE(calibrated.find("Includes an empirical term (not a named cause): " +
                              report::escape_xml(c.calibrated.friction->terms.front().symbol(1))),
              std::string::npos);
    EXPECT_NE(calibrated.find("are extrapolation"), std::string::npos);
  }
}

}  // namespace
}  // namespace lmcal
