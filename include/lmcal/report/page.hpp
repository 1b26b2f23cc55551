// An HTML page as lmcal's reports build it (the calibration report, prediction.html, plan.html,
// the fleet's report): headings, paragraphs, tables of escaped text and figures of SVG plots
// (svg_plot.hpp), the page collecting its plots' IDs; html_document wraps it in the reports'
// style and script. A front end that renders a page of its own (lmcal fleet) builds it here.
//
//   report::Page page;
//   page.heading(1, "lmcal fleet: units");
//   page.table({"unit", "mu_v"}, std::vector<std::vector<std::string>>{{"1", report::num(0.0123)}});
//   page.figures({plot});
//   const std::string html = report::html_document("lmcal fleet", page);
//
// Trap: text is escaped everywhere except `page << html`, which takes HTML as it is.
#pragma once

#include "lmcal/export.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "lmcal/report/svg_plot.hpp"

namespace LMCAL_API lmcal {
namespace report {

// A table cell: text, escaped when the page is built, and how lmcal draws it (a number's
// alignment, a shade it computed). There is no way for text to become HTML.
struct Cell {
  std::string text;
  bool number = false;
  std::string background;  // a CSS colour lmcal made ("rgba(0,114,178,0.40)"), or empty
  Cell(std::string t) : text(std::move(t)) {}
  Cell(const char* t) : text(t) {}
  Cell(std::string t, bool is_number, std::string shade) : text(std::move(t)), number(is_number), background(std::move(shade)) {}
};

class Page {
 public:
  Page& operator<<(std::string_view html) {
    html_ += html;
    return *this;
  }
  // A row of figures (they wrap on a narrow window).
  void figures(const std::vector<Plot>& plots) {
    html_ += "<div class=\"figures\">";
    for (const auto& p : plots) {
      ids_.push_back(p.id);
      html_ += "<figure>" + render_svg(p) + "</figure>";
    }
    html_ += "</div>\n";
  }
  void heading(int level, std::string_view text, std::string_view id = {}) {
    html_ += fmt::format("<h{0}{1}>{2}</h{0}>\n", level, id.empty() ? "" : fmt::format(" id=\"{}\"", id),
                         escape_xml(text));
  }
  void paragraph(std::string_view text, std::string_view css_class = {}) {
    html_ += fmt::format("<p{}>{}</p>\n", css_class.empty() ? "" : fmt::format(" class=\"{}\"", css_class),
                         escape_xml(text));
  }
  // A table of text cells (escaped), or of Cells (escaped, with lmcal's shading).
  template <typename C>
  void table(const std::vector<std::string>& header, const std::vector<std::vector<C>>& rows) {
    html_ += "<table><thead><tr>";
    for (const auto& h : header) html_ += "<th>" + escape_xml(h) + "</th>";
    html_ += "</tr></thead><tbody>\n";
    for (const auto& row : rows) {
      html_ += "<tr>";
      for (const auto& cell : row) html_ += td(Cell(cell));
      html_ += "</tr>\n";
    }
    html_ += "</tbody></table>\n";
  }
  const std::string& html() const { return html_; }
  const std::vector<std::string>& plot_ids() const { return ids_; }

 private:
  static std::string td(const Cell& cell) {
    return fmt::format("<td{}{}>{}</td>", cell.number ? " class=\"num\"" : "",
                       cell.background.empty() ? "" : fmt::format(" style=\"background:{}\"", escape_xml(cell.background)),
                       escape_xml(cell.text));
  }

  std::string html_;
  std::vector<std::string> ids_;
};

// A number to 4 significant digits, "–" when it is not finite.
inline std::string num(double v, int digits = 4) {
  return std::isfinite(v) ? fmt::format("{:.{}g}", v, digits) : "–";
}

// "[low, high]".
inline std::string bracket(double low, double high) { return fmt::format("[{}, {}]", num(low), num(high)); }

// A plot ID from free text: letters, digits and '-' only.
inline std::string plot_id(std::string_view text) {
  std::string id;
  for (char ch : text) id += std::isalnum(static_cast<unsigned char>(ch)) ? static_cast<char>(std::tolower(ch)) : '-';
  return id;
}

// Every n-th index so that at most `most` of `count` remain.
inline std::size_t stride(std::size_t count, std::size_t most) { return std::max<std::size_t>(1, (count + most - 1) / most); }

// A whole page: the report's style, `body`, and its one script: the checks the browser test
// reads (data-plots, data-rendered, …) and the plots' hover tooltips (values at the nearest
// point or line vertex). Opens offline; without script the points' own <title>s still show.
std::string html_document(std::string_view title, const Page& body);

}  // namespace report
}  // namespace lmcal
