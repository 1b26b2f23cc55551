#include "lmcal/io/resample.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "lmcal/error.hpp"

namespace lmcal {

namespace {

// A trace with the same channels (names, report) and no samples, room for `size`.
ThermalTrace empty_like(const ThermalTrace& trace, std::size_t size) {
  ThermalTrace out;
  out.report = trace.report;  // still describes the file as loaded
  out.time_s.reserve(size);
  for (const auto& [from, to] : {std::pair{&trace.ambient, &out.ambient}, std::pair{&trace.rail, &out.rail}}) {
    for (const TemperatureChannel& channel : *from) {
      to->push_back({channel.name, {}});
      to->back().values.reserve(size);
    }
  }
  return out;
}

// Applies `f(source values, destination values)` to every temperature channel.
template <typename F>
void for_each_channel(const ThermalTrace& in, ThermalTrace& out, F&& f) {
  for (std::size_t c = 0; c < in.ambient.size(); ++c) f(in.ambient[c].values, out.ambient[c].values);
  for (std::size_t c = 0; c < in.rail.size(); ++c) f(in.rail[c].values, out.rail[c].values);
}

void require_count(const char* parameter, std::size_t n) {
  if (n == 0) throw InvalidParameter(parameter, 0.0, "an integer >= 1");
}

}  // namespace

ThermalTrace decimate(const ThermalTrace& trace, std::size_t every) {
  require_count("every", every);
  const std::size_t size = (trace.size() + every - 1) / every;
  ThermalTrace out = empty_like(trace, size);
  for (std::size_t i = 0; i < trace.size(); i += every) out.time_s.push_back(trace.time_s[i]);
  for_each_channel(trace, out, [&](const std::vector<double>& in, std::vector<double>& to) {
    for (std::size_t i = 0; i < in.size(); i += every) to.push_back(in[i]);
  });
  return out;
}

ThermalTrace block_average(const ThermalTrace& trace, std::size_t block) {
  require_count("block", block);
  const std::size_t size = (trace.size() + block - 1) / block;
  ThermalTrace out = empty_like(trace, size);
  // Mean of [begin, end), leaving NaN samples out; NaN when none is valid.
  const auto mean = [](const std::vector<double>& v, std::size_t begin, std::size_t end) {
    double sum = 0;
    std::size_t n = 0;
    for (std::size_t i = begin; i < end; ++i) {
      if (std::isnan(v[i])) continue;
      sum += v[i];
      ++n;
    }
    return n ? sum / static_cast<double>(n) : std::numeric_limits<double>::quiet_NaN();
  };
  const auto blocks = [&](const std::vector<double>& in, std::vector<double>& to) {
    for (std::size_t begin = 0; begin < in.size(); begin += block) {
      to.push_back(mean(in, begin, std::min(begin + block, in.size())));  // the last block may be partial
    }
  };
  blocks(trace.time_s, out.time_s);
  for_each_channel(trace, out, blocks);
  return out;
}

}  // namespace lmcal
