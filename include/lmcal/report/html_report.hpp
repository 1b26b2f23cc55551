// The calibration report: one self-contained HTML file (inline SVG plots and style, no
// external resource, opens offline) telling the whole story of a calibration.
//
//   brief      the verdicts and the headline numbers, one screen
//   friction   measured vs fitted force over velocity by load, preload and temperature (the
//              paper's Fig. 6), the constants with intervals and correlations, residuals
//              against every covariate, the spread across runs, the diagnosis before/after
//   thermal    α with its interval, the error against α (Fig. 11), temperature vs time per
//              sensor (Figs. 14-15) and along the rail at the end of each run with the
//              measured points (Fig. 16), residuals, the spread across runs, the diagnosis
//              before/after
//   inputs     the files and their SHA-256, the command, the versions
//
// Every plot is an <svg data-plot="ID">; the page lists the IDs it should hold in
// <body data-plots="ID ID …">, and a small inline script marks <body data-rendered> with the
// plots that did not draw (a browser test reads it; the page needs no script to be read).
#pragma once

#include <string>
#include <vector>

#include "lmcal/report/calibration.hpp"

namespace lmcal {

std::string calibration_report_html(const Calibration& c);

// The IDs of the plots the report of `c` holds, in page order.
std::vector<std::string> calibration_report_plots(const Calibration& c);

}  // namespace lmcal
