// What every libFuzzer harness of fuzz/ shares: the fuzz bytes as a file of the process's own,
// and the properties each loader must keep besides not crashing —
//   (a) the only exception that leaves a loader is lmcal::InputError,
//   (b) its message starts with the file it is about, and with a line where the format has lines,
//   (c) nothing non-finite gets past a loader (NaN only where the format documents it as missing),
//   (d) a log that loads writes back with the project's writer and reloads to the same data.
// A broken property aborts with "lmcal fuzz finding: ...", which libFuzzer saves as a crash.
//
// The round trips compare exactly: the writers print every number in its shortest form that
// reads back to the same double (CsvText::cell, toml_number), in the internal unit (conversion
// factor 1, offset 0), so a reloaded value that differs at all is a finding.
#pragma once

#include <cxxabi.h>
#include <fmt/format.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <typeinfo>
#include <utility>
#include <vector>

#include "lmcal/error.hpp"
#include "lmcal/io/catalog.hpp"
#include "lmcal/io/friction_log.hpp"
#include "lmcal/io/thermal_run.hpp"
#include "lmcal/io/units.hpp"
#include "io/input_file.hpp"

namespace lmcal::fuzz {

namespace fs = std::filesystem;

[[noreturn]] inline void finding(const std::string& what) {
  std::fprintf(stderr, "lmcal fuzz finding: %s\n", what.c_str());
  std::abort();
}

// A temporary folder of this process's own (libFuzzer's -jobs run harnesses side by side),
// removed at a normal exit and kept after a finding, to look at.
inline const fs::path& work_dir() {
  static const struct Dir {
    fs::path path;
    Dir() {
      std::string pattern = (fs::temp_directory_path() / "lmcal-fuzz-XXXXXX").string();
      if (!mkdtemp(pattern.data())) {
        std::perror("lmcal fuzz: mkdtemp");
        std::exit(2);
      }
      path = pattern;
    }
    ~Dir() {
      std::error_code ec;
      fs::remove_all(path, ec);
    }
  } dir;
  return dir.path;
}

inline fs::path write_file(const std::string& name, std::string_view bytes) {
  const fs::path path = work_dir() / name;
  std::ofstream(path, std::ios::binary | std::ios::trunc).write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  return path;
}

inline std::string_view as_text(const std::uint8_t* data, std::size_t size) {
  return {reinterpret_cast<const char*>(data), size};
}

// The files a manifest harness reads besides the manifest (fuzz/companions, copied beside it
// once per process), so that a fuzzed manifest can name a valid file.
inline void copy_companions() {
  static const bool copied = [] {
    fs::copy(LMCAL_FUZZ_COMPANIONS, work_dir(), fs::copy_options::recursive | fs::copy_options::overwrite_existing);
    return true;
  }();
  (void)copied;
}

inline std::string type_name(const std::type_info& type) {
  int status = 0;
  const std::unique_ptr<char, decltype(&std::free)> name(abi::__cxa_demangle(type.name(), nullptr, nullptr, &status),
                                                         &std::free);
  return status == 0 ? name.get() : type.name();
}

// Refusals about a whole file rather than a place in it: no line to name.
inline bool whole_file_refusal(std::string_view message) {
  for (const std::string_view whole : {"empty file", "this looks like", "no [[run]] tables",
                                       "expected one or more [[guide]] or [[bar]] tables", "cannot open", "cannot read"})
    if (message.find(whole) != std::string_view::npos) return true;
  return false;
}

// (b): an InputError names the file it is about first: one of `files` (what the harness
// wrote) or a file the input named (a manifest's CSV or catalog, which exists); `lines`: the
// format has lines, so the message names one unless it is about the whole file.
inline void check_refusal(const InputError& e, const std::vector<fs::path>& files, bool lines) {
  const std::string message = e.what();
  bool known = false;
  for (const fs::path& f : files) known = known || e.file() == f.string();
  std::error_code ec;
  if (e.file().empty() || !message.starts_with(e.file()) || !(known || fs::is_regular_file(e.file(), ec)))
    finding(fmt::format("an InputError that does not start with the file it is about: file '{}', message '{}'",
                        e.file(), message));
  if (lines && e.line() <= 0 && !whole_file_refusal(message))
    finding(fmt::format("an InputError without a line: {}", message));
}

// (a) and (b): the loader's result, or nullopt when it refused the input as it should.
template <class Load>
auto loaded_or_refused(Load&& load, const std::vector<fs::path>& files, bool lines) -> std::optional<decltype(load())> {
  try {
    return load();
  } catch (const InputError& e) {
    check_refusal(e, files, lines);
  } catch (const std::exception& e) {
    finding(fmt::format("{} escaped the loader: {}", type_name(typeid(e)), e.what()));
  } catch (...) {
    finding("an exception not derived from std::exception escaped the loader");
  }
  return std::nullopt;
}

// ---- (c) finite -----------------------------------------------------------------------------

inline void finite(double v, std::string_view field) {
  if (!std::isfinite(v)) finding(fmt::format("{} = {} got past the loader", field, v));
}
inline void finite(const std::optional<double>& v, std::string_view field) {
  if (v) finite(*v, field);
}
// `missing_ok`: NaN is the format's missing value here; ±inf never is.
inline void finite(const std::vector<double>& values, std::string_view field, bool missing_ok = false) {
  for (const double v : values)
    if (!(missing_ok && std::isnan(v))) finite(v, field);
}
inline void finite(const std::map<std::string, double>& values, std::string_view field) {
  for (const auto& [name, v] : values) finite(v, fmt::format("{}.{}", field, name));
}

inline void check_loaded(const GuideSpec& spec) {
  for (const std::string& name : guide_field_names()) finite(field_value(spec, name), spec.model + "." + name);
}

// A friction log's numbers per sample, time aside (NaN there: the file has no time column).
struct FrictionColumn {
  std::vector<double> FrictionLog::*values;
  const char* name;
  Quantity quantity;
};
inline constexpr std::array<FrictionColumn, 7> kFrictionColumns{{
    {&FrictionLog::velocity_m_s, "velocity_m_s", Quantity::velocity},
    {&FrictionLog::load_N, "load_N", Quantity::force},
    {&FrictionLog::preload_um, "preload_um", Quantity::preload},
    {&FrictionLog::block_length_mm, "block_length_mm", Quantity::length_mm},
    {&FrictionLog::temperature_C, "temperature_C", Quantity::temperature},
    {&FrictionLog::friction_N, "friction_N", Quantity::force},
    {&FrictionLog::viscosity40_mm2_s, "viscosity40_mm2_s", Quantity::viscosity},
}};

// ... and within the range of a rig's values (units.hpp physical_range), NaN aside.
inline void in_range(const std::vector<double>& values, std::string_view field, const PhysicalRange& range) {
  for (const double v : values)
    if (!std::isnan(v) && !range.contains(v)) finding(fmt::format("{} = {} (beyond {:g} to {:g}) got past the loader", field, v, range.low, range.high));
}

// Names fit for outputs (io::name_problem), or a finding.
inline void printable_names(const std::vector<std::string>& names, std::string_view what) {
  for (const std::string& name : names)
    if (auto problem = io::name_problem(name)) finding(fmt::format("{} '{}' got past the loader: {}", what, io::printable(name), *problem));
}

inline void check_loaded(const FrictionLog& log) {
  const std::size_t n = log.size();
  if (log.time_s.size() != n || log.run.size() != n || log.guide.size() != n || log.direction.size() != n)
    finding("friction log columns of different lengths");
  finite(log.time_s, "time_s", true);
  in_range(log.time_s, "time_s", physical_range(Quantity::time));
  for (const auto& [column, name, quantity] : kFrictionColumns) {
    if ((log.*column).size() != n) finding("friction log columns of different lengths");
    finite(log.*column, name);
    in_range(log.*column, name, physical_range(quantity));
  }
  printable_names(log.run_names, "run name");
  printable_names(log.guide_names, "guide name");
  for (std::size_t i = 0; i < n; ++i) {
    if (log.run[i] >= log.run_names.size() || log.guide[i] >= log.guide_names.size())
      finding("friction log sample with a run or guide index out of range");
    if (log.direction[i] != 1 && log.direction[i] != -1) finding(fmt::format("direction = {}", log.direction[i]));
  }
  for (const RawTrace& t : log.raw_traces) {
    finite(t.time_s, "raw trace time_s");
    finite(t.velocity_m_s, "raw trace velocity_m_s");
    finite(t.force_N, "raw trace force_N");
  }
  for (const RunSegmentation& s : log.segmentation)
    for (const Plateau& p : s.plateaus) {
      finite(p.start_s, "plateau start_s");
      finite(p.end_s, "plateau end_s");
      finite(p.velocity_m_s, "plateau velocity_m_s");
    }
}

inline void check_loaded(const ThermalTrace& trace) {
  finite(trace.time_s, "time_s");
  in_range(trace.time_s, "time_s", physical_range(Quantity::time));
  finite(trace.heat_rate_W, "heat_rate_W");
  in_range(trace.heat_rate_W, "heat_rate_W", kHeatRateRange);
  if (!trace.heat_rate_W.empty() && trace.heat_rate_W.size() != trace.size()) finding("heat_rate_W of another length");
  for (const auto* group : {&trace.ambient, &trace.rail})
    for (const TemperatureChannel& c : *group) {
      if (c.values.size() != trace.size()) finding("temperature channel of another length than time_s");
      finite(c.values, c.name, true);  // NaN: a missing sample
      in_range(c.values, c.name, physical_range(Quantity::temperature));
      printable_names({c.name}, "column name");
    }
}

// ---- (d) round trips ------------------------------------------------------------------------

inline bool same(double a, double b) { return a == b || (std::isnan(a) && std::isnan(b)); }

inline void expect_same(bool equal, std::string_view what, std::size_t i) {
  if (!equal) finding(fmt::format("written and reloaded, {} differs (at {})", what, i));
}

inline void expect_same(const std::vector<double>& a, const std::vector<double>& b, std::string_view what) {
  expect_same(a.size() == b.size(), what, a.size());
  for (std::size_t i = 0; i < a.size(); ++i) expect_same(same(a[i], b[i]), what, i);
}

// The reloaded file, refused or not: a refusal of what the writer wrote is a finding too.
template <class Load>
auto reloaded(Load&& load, std::string_view what) {
  try {
    return load();
  } catch (const std::exception& e) {
    finding(fmt::format("{} written by lmcal does not load back: {}", what, e.what()));
  }
}

// Samples compared by run and guide name (a run whose rows were all skipped has a name but no
// sample, and is not written).
inline void check_round_trip(const FrictionLog& log) {
  if (log.size() == 0) return;  // a header alone is refused ("no data rows")
  const fs::path file = write_file("roundtrip.csv", friction_log_csv(log));
  const FrictionLog back = reloaded([&] { return load_friction_log(file); }, "friction_log_csv");
  expect_same(back.size() == log.size(), "the sample count", log.size());
  for (std::size_t i = 0; i < log.size(); ++i) {
    expect_same(back.run_names[back.run[i]] == log.run_names[log.run[i]], "run", i);
    expect_same(back.guide_names[back.guide[i]] == log.guide_names[log.guide[i]], "guide", i);
    expect_same(back.direction[i] == log.direction[i], "direction", i);
  }
  // The writer leaves the time column out unless every sample has a time (several files, some
  // without one): then none comes back.
  if (std::none_of(log.time_s.begin(), log.time_s.end(), [](double t) { return std::isnan(t); }))
    expect_same(log.time_s, back.time_s, "time_s");
  else
  for (const FrictionColumn& c : kFrictionColumns) expect_same(log.*c.values, back.*c.values, c.name);
  for (const auto& [column, name, quantity] : kFrictionColumns) expect_same(log.*column, back.*column, name);
}

// Channels compared by name without the unit: the writer converts "tc1_K" to "tc1_C".
inline void expect_same(const ThermalTrace& a, const ThermalTrace& b) {
  expect_same(a.time_s, b.time_s, "time_s");
  expect_same(a.heat_rate_W, b.heat_rate_W, "heat_rate_W");
  const auto base = [](const std::string& name) {
    const auto split = split_unit(name, Quantity::temperature);
    return split ? split->name : name;
  };
  for (const auto& [group, other] : {std::pair(&a.ambient, &b.ambient), std::pair(&a.rail, &b.rail)}) {
    expect_same(group->size() == other->size(), "the channel count", group->size());
    for (std::size_t c = 0; c < group->size(); ++c) {
      expect_same(base((*group)[c].name) == base((*other)[c].name), "a channel name", c);
      expect_same((*group)[c].values, (*other)[c].values, (*group)[c].name);
    }
  }
}

}  // namespace lmcal::fuzz
