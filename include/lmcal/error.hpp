// Errors lmcal raises, and the one assertion macro for internal invariants.
//
// Bad input is an exception that says where and what: InputError carries the
// file, line and column (1-based; 0 = not applicable) and what was expected.
// A non-physical parameter is an InvalidParameter naming the parameter and its
// value. Numerical outcomes (a fit at a bound, a singular covariance) are not
// exceptions: they are reported in the result structs.
#pragma once

#include "lmcal/export.hpp"

#include <cmath>
#include <stdexcept>
#include <string>

namespace LMCAL_API lmcal {

class InputError : public std::runtime_error {
 public:
  InputError(std::string file, long line, long column, const std::string& what);
  const std::string& file() const { return file_; }
  long line() const { return line_; }
  long column() const { return column_; }

 private:
  std::string file_;
  long line_;
  long column_;
};

class InvalidParameter : public std::invalid_argument {
 public:
  InvalidParameter(std::string parameter, double value, const std::string& expected);
  InvalidParameter(std::string parameter, const std::string& message);
  const std::string& parameter() const { return parameter_; }

 private:
  std::string parameter_;
};

// The InvalidParameter the checks below raise; out of line, so that the checks inline.
[[noreturn]] void throw_invalid(const char* parameter, double value, const char* expected);
[[noreturn]] void throw_out_of_range(const char* parameter, double value, double lo, double hi);

// Throws InvalidParameter unless `value` is finite and satisfies the named bound.
inline void require_finite(const char* parameter, double value) {
  if (!std::isfinite(value)) [[unlikely]]
    throw_invalid(parameter, value, "a finite number");
}
inline void require_positive(const char* parameter, double value) {
  if (!(std::isfinite(value) && value > 0)) [[unlikely]]
    throw_invalid(parameter, value, "a finite value > 0");
}
inline void require_non_negative(const char* parameter, double value) {
  if (!(std::isfinite(value) && value >= 0)) [[unlikely]]
    throw_invalid(parameter, value, "a finite value >= 0");
}
inline void require_in_range(const char* parameter, double value, double lo, double hi) {
  if (!(std::isfinite(value) && value >= lo && value <= hi)) [[unlikely]]
    throw_out_of_range(parameter, value, lo, hi);
}

[[noreturn]] void assertion_failed(const char* expr, const char* file, int line, const char* message);

}  // namespace lmcal

// Internal invariant: aborts with the expression, location and a message. Not for user input.
#define LMCAL_ASSERT(expr, message) \
  ((expr) ? static_cast<void>(0) : ::lmcal::assertion_failed(#expr, __FILE__, __LINE__, message))
