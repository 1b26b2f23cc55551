// Errors lmcal raises, and the one assertion macro for internal invariants.
//
// Bad input is an exception that says where and what: InputError carries the
// file, line and column (1-based; 0 = not applicable) and what was expected.
// A non-physical parameter is an InvalidParameter naming the parameter and its
// value. Numerical outcomes (a fit at a bound, a singular covariance) are not
// exceptions: they are reported in the result structs.
#pragma once

#include "lmcal/export.hpp"

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

// Throws InvalidParameter unless `value` is finite and satisfies the named bound.
void require_finite(const char* parameter, double value);
void require_positive(const char* parameter, double value);
void require_non_negative(const char* parameter, double value);
void require_in_range(const char* parameter, double value, double lo, double hi);

[[noreturn]] void assertion_failed(const char* expr, const char* file, int line, const char* message);

}  // namespace lmcal

// Internal invariant: aborts with the expression, location and a message. Not for user input.
#define LMCAL_ASSERT(expr, message) \
  ((expr) ? static_cast<void>(0) : ::lmcal::assertion_failed(#expr, __FILE__, __LINE__, message))
