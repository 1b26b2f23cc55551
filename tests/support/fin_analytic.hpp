// Closed-form steady state of the half-rail fin with a uniform source on 0 <= x <= a,
// no source on a < x <= ℓ, symmetric at 0 and convective at ℓ (shared/PHYSICS.md §4).
//
//   θ'' - m² θ = -s  (x <= a),   θ'' - m² θ = 0  (x > a),   θ = T - T∞,
//   m² = (h p + b) / (k A),  s = g / (k A),  θ'(0) = 0,  -k θ'(ℓ) = h θ(ℓ).
//
//   x <= a:  θ = s/m² + B cosh(m x)
//   x >  a:  θ = C [cosh(m(ℓ - x)) + β sinh(m(ℓ - x))],  β = h / (k m)
// with B and C from continuity of θ and θ' at x = a.
#pragma once

#include <cmath>

namespace lmcal::test {

struct FinAnalytic {
  double m, s, a, ell, beta, B, C;

  // base_loss_W_mK adds to the side loss h p (heat lost through the rail base).
  FinAnalytic(double h, double perimeter, double k, double area, double line_power_W_m, double a_m, double ell_m,
              double base_loss_W_mK = 0.0)
      : m(std::sqrt((h * perimeter + base_loss_W_mK) / (k * area))), s(line_power_W_m / (k * area)), a(a_m), ell(ell_m),
        beta(h / (k * m)) {
    const double u = m * (ell - a);
    const double E = std::cosh(u) + beta * std::sinh(u);   // θ(a+)/C
    const double dE = -m * (std::sinh(u) + beta * std::cosh(u));  // θ'(a+)/C
    // s/m² + B cosh(ma) = C E;  B m sinh(ma) = C dE
    const double ch = std::cosh(m * a), sh = std::sinh(m * a);
    C = (s / (m * m)) / (E - dE * ch / (m * sh));
    B = C * dE / (m * sh);
  }

  double excess_K(double x) const {
    if (x <= a) return s / (m * m) + B * std::cosh(m * x);
    return C * (std::cosh(m * (ell - x)) + beta * std::sinh(m * (ell - x)));
  }
};

}  // namespace lmcal::test
