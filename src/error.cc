#include "lmcal/error.hpp"

#include <fmt/format.h>

#include <cstdio>
#include <cstdlib>

namespace lmcal {

namespace {
std::string locate(const std::string& file, long line, long column) {
  std::string where = file;
  if (line > 0) where += fmt::format(":{}", line);
  if (column > 0) where += fmt::format(":{}", column);
  return where;
}
}  // namespace

InputError::InputError(std::string file, long line, long column, const std::string& what)
    : std::runtime_error(fmt::format("{}: {}", locate(file, line, column), what)),
      file_(std::move(file)),
      line_(line),
      column_(column) {}

InvalidParameter::InvalidParameter(std::string parameter, double value, const std::string& expected)
    : std::invalid_argument(fmt::format("{} = {} is invalid: expected {}", parameter, value, expected)),
      parameter_(std::move(parameter)) {}

InvalidParameter::InvalidParameter(std::string parameter, const std::string& message)
    : std::invalid_argument(fmt::format("{}: {}", parameter, message)), parameter_(std::move(parameter)) {}

void throw_invalid(const char* parameter, double value, const char* expected) {
  throw InvalidParameter(parameter, value, expected);
}

void throw_out_of_range(const char* parameter, double value, double lo, double hi) {
  throw InvalidParameter(parameter, value, fmt::format("a value in [{}, {}]", lo, hi));
}

void assertion_failed(const char* expr, const char* file, int line, const char* message) {
  std::fprintf(stderr, "lmcal: internal error at %s:%d: %s (%s)\n", file, line, message, expr);
  std::abort();
}

}  // namespace lmcal
