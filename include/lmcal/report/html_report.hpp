// The calibration report: one self-contained HTML file (inline SVG plots and style, no
// external resource, opens offline) telling the whole story of a calibration.
//
//   calibrated the first screen: the calibrated model (the published law and rail model with
//              the causes the diagnoses accepted, refitted; see calibration.hpp), every
//              parameter with SE, quoted 95 % interval and the covariance it comes from, the
//              held-out RMSE, the heat's share of α's variance, the caveats; model.toml
//   verdicts   the diagnoses' verdicts and the published models' headline numbers
//   how sure   per calibrated fit: the SE of every covariance method side by side (iid, hac,
//              cluster, bootstrap, heat) and the quoted one over iid, lag-1 autocorrelation,
//              effective sample size, HAC lags, the between-run tests, correlations, and each
//              run's own estimate (α; the friction constants) against the pooled 95 % interval
//   friction   the published law, labelled "for comparison; conditional on a model the
//              diagnosis rejects" when the diagnosis accepted causes: measured vs fitted force
//              over velocity by load, preload and temperature (the paper's Fig. 6), the
//              constants with intervals and correlations, residuals against every covariate,
//              the spread across runs, the diagnosis before/after (the parameters that move,
//              both values with their intervals)
//   thermal    the published rail model, labelled likewise: α with its interval, the error
//              against α (Fig. 11), temperature vs time per sensor (Figs. 14-15) and along the
//              rail at the end of each run with the measured points (Fig. 16), residuals, the
//              spread across runs, the diagnosis before/after
//   inputs     the files and their SHA-256, the command, the versions
//
// Every plot is an <svg data-plot="ID">; the page lists the IDs it should hold in
// <body data-plots="ID ID …">, and a small inline script marks <body data-rendered> with the
// plots that did not draw (a browser test reads it; the page needs no script to be read).
#pragma once

#include "lmcal/export.hpp"

#include <string>
#include <vector>

#include "lmcal/calibrate/calibration.hpp"

namespace LMCAL_API lmcal {

std::string calibration_report_html(const Calibration& c);

// The IDs of the plots the report of `c` holds, in page order.
std::vector<std::string> calibration_report_plots(const Calibration& c);

}  // namespace lmcal
