// The scalar types the templated physics is compiled for, written once (Drake's
// DRAKE_DEFINE_CLASS_TEMPLATE_INSTANTIATIONS_ON_DEFAULT_SCALARS): double for simulation, and
// the ceres::Jet sizes a thermal run's derivatives use (private to the library).
//
// A thermal run depends on at most 8 parameters (α, h, a mechanism's, its offsets, its T0;
// the fit checks it) and is simulated with the smallest Jet that holds them, so the rail
// solver is instantiated for these five types and nothing else:
//   #define INSTANTIATE(T) template RailSolution<T> simulate_rail<T>(…);
//   LMCAL_FOR_EACH_AUTODIFF_SCALAR(INSTANTIATE)
// A table over the types (one function pointer each) is a std::tuple of AutodiffScalars.
//
// Trap: a macro argument cannot hold a comma, so the list names the aliases Jet1 … Jet8,
// never ceres::Jet<double, N>.
#pragma once

#include <ceres/jet.h>

#include <tuple>

namespace lmcal {

using Jet1 = ceres::Jet<double, 1>;
using Jet2 = ceres::Jet<double, 2>;
using Jet4 = ceres::Jet<double, 4>;
using Jet8 = ceres::Jet<double, 8>;

// The same list as a type, for tables and dispatch.
using AutodiffScalars = std::tuple<double, Jet1, Jet2, Jet4, Jet8>;

}  // namespace lmcal

// X(T) for every scalar of AutodiffScalars, in its order.
#define LMCAL_FOR_EACH_AUTODIFF_SCALAR(X) X(double) X(::lmcal::Jet1) X(::lmcal::Jet2) X(::lmcal::Jet4) X(::lmcal::Jet8)
// X(N) for every Jet size of AutodiffScalars, smallest first.
#define LMCAL_FOR_EACH_JET_SIZE(X) X(1) X(2) X(4) X(8)
