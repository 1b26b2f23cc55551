#include "lmcal/io/friction_log.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <map>
#include <memory>
#include <optional>

#include "io/csv_reader.hpp"
#include "io/friction_files.hpp"
#include "io/input_file.hpp"
#include "io/raw_friction.hpp"
#include "parallel_slices.hpp"
#include "lmcal/error.hpp"
#include "lmcal/io/csv_writer.hpp"
#include "lmcal/io/limits.hpp"

namespace lmcal {

namespace {

namespace fs = std::filesystem;
using csv::Rule;

constexpr double kDefaultViscosity40_mm2_s = 99.0;  // ν_i of Eq. 6 (PHYSICS.md §2)

// The columns of a friction log, in the order the writer puts them; a raw log's last.
enum Spec : std::size_t {
  kRun,
  kGuide,
  kTime,
  kVelocity,
  kLoad,
  kPreload,
  kBlockLength,
  kTemperature,
  kFriction,
  kViscosity40,
  kDirection,
  kForce,
  kPosition,
  kAngularVelocity,  // a motor's speed: becomes kVelocity through the drive
  kTorque,           // a motor's torque: becomes kForce through the drive
  kAcceleration      // a tidy log's: the carriage's, where its friction was taken
};
// Required columns are checked by the loader: a manifest may give them instead, and a raw log
// has force where a tidy one has friction.
constexpr std::array<csv::ColumnSpec, 16> kSpecs{{
    {.name = "run", .text = true},
    {.name = "guide", .text = true},
    {.name = "time", .quantity = Quantity::time},
    {.name = "velocity",
     .quantity = Quantity::velocity,
     .rule = Rule::non_negative,
     .hint = " (a speed; the direction column gives the sense)"},
    {.name = "load", .quantity = Quantity::force, .rule = Rule::non_negative},
    {.name = "preload", .quantity = Quantity::preload, .rule = Rule::non_negative},
    {.name = "block_length", .quantity = Quantity::length_mm, .rule = Rule::positive},
    {.name = "temperature", .quantity = Quantity::temperature, .rule = Rule::above_absolute_zero},
    {.name = "friction", .quantity = Quantity::force},
    {.name = "viscosity40", .quantity = Quantity::viscosity, .rule = Rule::positive},
    {.name = "direction", .rule = Rule::plus_or_minus_one},
    {.name = "force", .quantity = Quantity::force},
    {.name = "position", .quantity = Quantity::distance_m},
    {.name = "velocity",
     .quantity = Quantity::angular_velocity,
     .rule = Rule::non_negative,
     .hint = " (a speed; the direction column gives the sense)"},
    {.name = "torque", .quantity = Quantity::torque},
    {.name = "acceleration", .quantity = Quantity::acceleration},
}};

std::string header_of(Spec spec) {
  const csv::ColumnSpec& s = kSpecs[spec];
  return s.quantity ? csv::canonical_name(s.name, *s.quantity) : std::string(s.name);
}

// Name -> index in first-appearance order, shared by all files of a log. Rows of one run
// come in blocks, so the previous name is checked before the map.
class NameIndex {
 public:
  explicit NameIndex(std::vector<std::string>& names) : names_(names) {}
  std::uint32_t operator()(std::string_view name) {
    if (last_ && name == names_[*last_]) return *last_;
    auto it = index_.find(name);
    if (it == index_.end()) {
      it = index_.emplace(std::string(name), static_cast<std::uint32_t>(names_.size())).first;
      names_.emplace_back(name);
    }
    last_ = it->second;
    return it->second;
  }
  std::size_t size() const { return names_.size(); }

 private:
  std::vector<std::string>& names_;
  std::map<std::string, std::uint32_t, std::less<>> index_;
  std::optional<std::uint32_t> last_;
};

// Each of a part's local names (runs or guides) as the joined log's index, in the order they
// first appear; `Refusal` thrown when the names pass the limit (the reading that joins them
// refuses the file, as one reader would have).
template <typename Refusal>
std::vector<std::uint32_t> map_names(NameIndex& names, const std::vector<std::string>& local) {
  std::vector<std::uint32_t> map;
  for (const std::string& name : local) map.push_back(names(name));
  if (names.size() > io::kMaxRuns) throw Refusal();
  return map;
}

// The text of a run or guide cell; an empty name is an error.
std::string_view name_cell(const csv::Reader& reader, const csv::Column& column, std::string& scratch) {
  const std::string_view name = reader.text(column.cell, scratch);
  if (name.empty())
    reader.fail(column.cell, fmt::format("column '{}': expected a name, found an empty cell", column.header));
  return name;
}

// The run conditions a manifest may give instead of columns.
struct ConditionKey {
  Spec spec;
  std::optional<double> FrictionRunConditions::*field;
  bool required;
};
constexpr std::array<ConditionKey, 5> kConditionKeys{{
    {kLoad, &FrictionRunConditions::load_N, true},
    {kPreload, &FrictionRunConditions::preload_um, true},
    {kBlockLength, &FrictionRunConditions::block_length_mm, true},
    {kTemperature, &FrictionRunConditions::temperature_C, true},
    {kViscosity40, &FrictionRunConditions::viscosity40_mm2_s, false},
}};

// The conditions of a raw sample besides its motion: they rarely change within a run, so each
// sample keeps an index into a table of them.
struct SampleSetup {
  std::uint32_t guide = 0;
  FrictionConditions<double> conditions;  // velocity and direction unset
  double viscosity40 = 0;
  bool operator==(const SampleSetup& o) const {
    return guide == o.guide && viscosity40 == o.viscosity40 && conditions.load_N == o.conditions.load_N &&
           conditions.preload_um == o.conditions.preload_um &&
           conditions.block_length_mm == o.conditions.block_length_mm &&
           conditions.temperature_C == o.conditions.temperature_C;
  }
};

// One raw run of a file as read: samples in time order, duplicate times merged.
struct RawRun {
  std::uint32_t run = 0;
  raw::RunSamples samples;
  std::vector<long> line;             // of each sample (its first, when merged)
  std::uint32_t last_merged = 1;      // samples merged into the last one
  std::size_t merged = 0;             // samples merged into others
  std::vector<std::uint32_t> setup;   // of each sample: index into setups
  std::vector<SampleSetup> setups;

  void reserve(std::size_t n) {
    for (auto* v : {&samples.time_s, &samples.motion, &samples.force_N}) v->reserve(n);
    line.reserve(n);
    setup.reserve(n);
  }
  void add_setup(const SampleSetup& s) {
    if (setups.empty() || !(setups.back() == s)) setups.push_back(s);
    setup.push_back(static_cast<std::uint32_t>(setups.size() - 1));
  }
};

// A file of a log being read: its columns, where each condition comes from, the rows' checks.
class FileLoader {
 public:
  FileLoader(const detail::FrictionFile& file, const RawFrictionOptions& raw, FrictionLog& log, NameIndex& runs,
             NameIndex& guides)
      : file_(file), raw_(raw), log_(log), runs_(runs), guides_(guides),
        reader_(file.path, file.skip_lines.value_or(raw.skip_lines)) {
    report_.file = reader_.file();
    reader_.read_header();
    columns_ = csv::bind_header(reader_, kSpecs, report_);
    bind_drive();
    for (std::size_t spec = 0; spec < kSpecs.size(); ++spec) bound_[spec] = csv::find_column(columns_, spec);
    bind();
  }

  // Reads the rows: line by line when `sliced` is null; else a large tidy file in slices, one
  // per thread, setting *sliced first (what then throws is read again line by line by the
  // caller: see read_slices).
  void load(bool* sliced) {
    reserve(log_, log_.size() + reader_.estimated_rows());
    const int slices = sliced && !is_raw() ? detail::slice_threads(reader_.file_size(), kSliceBytes) : 1;
    if (slices > 1) {
      *sliced = true;
      read_slices(slices);
    } else {
      read_rows();
      report_.bytes = static_cast<double>(reader_.bytes());
    }
    if (report_.rows_read == 0) reader_.fail_at(reader_.header_line(), 0, "no data rows below the header");
    if (is_raw()) {
      segment_raw_runs();
    } else {
      if (skipped_ != 0) report_.skipped[column(kFriction)->header + " empty or NaN"] = skipped_;
      report_.rows_kept = report_.rows_read - skipped_;
      warn_signed_friction();
    }
    if (report_.rows_kept == 0) {  // a log of nothing is not a log: say what every row lacked
      std::vector<std::string> why;
      for (const auto& [reason, count] : report_.skipped) why.push_back(fmt::format("{} {}", count, reason));
      reader_.fail_at(reader_.header_line(), 0,
                      fmt::format("no sample kept of the {} rows read: {}", report_.rows_read, fmt::join(why, ", ")));
    }
    log_.reports.push_back(std::move(report_));
  }

  // Room for `capacity` rows in every column of `log`.
  static void reserve(FrictionLog& log, std::size_t capacity) {
    for (auto* v : {&log.time_s, &log.velocity_m_s, &log.load_N, &log.preload_um, &log.block_length_mm,
                    &log.temperature_C, &log.friction_N, &log.viscosity40_mm2_s, &log.acceleration_m_s2,
                    &log.position_m, &log.distance_since_reversal_m, &log.time_since_reversal_s}) {
      csv::reserve_rows(*v, capacity);
    }
    csv::reserve_rows(log.run, capacity);
    csv::reserve_rows(log.guide, capacity);
    csv::reserve_rows(log.direction, capacity);
    csv::reserve_rows(log.line, capacity);
  }

 private:
  static constexpr std::size_t kNone = static_cast<std::size_t>(-1);
  static constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
  struct LastSample {
    double time_s = kNaN;
    long line = 0;
    double first_s = kNaN;  // the run's first time in this file (or slice)
  };

  // Slices of a file read in parallel: at least this many bytes each.
  static constexpr std::size_t kSliceBytes = std::size_t{4} << 20;

  // A loader of `slice` of `whole`'s file, into `log` with names in `runs` and `guides`: the
  // same columns and conditions, the rows' state its own.
  FileLoader(const FileLoader& whole, std::string_view slice, long lines_before, FrictionLog& log, NameIndex& runs,
             NameIndex& guides)
      : file_(whole.file_), raw_(whole.raw_), log_(log), runs_(runs), guides_(guides),
        reader_(whole.reader_, slice, lines_before), columns_(whole.columns_),
        file_run_name_(whole.file_run_name_), law_(whole.law_), motion_kind_(whole.motion_kind_) {
    const auto same = [&](const csv::Column* c) { return c ? &columns_[static_cast<std::size_t>(c - whole.columns_.data())] : nullptr; };
    for (std::size_t spec = 0; spec < kSpecs.size(); ++spec) bound_[spec] = same(whole.bound_[spec]);
    motion_ = same(whole.motion_);
  }

  void read_rows() {
    std::string scratch;
    while (reader_.next()) {
      ++report_.rows_read;
      read_row(scratch);
    }
  }

  // What a slice's rows may not do for it to load as it would within the whole file: it throws
  // this (or the InputError of a bad row), and the caller reads the file line by line.
  struct SlicesDisagree : std::exception {
    const char* what() const noexcept override { return "the slices of a file read apart disagree"; }
  };

  // The rest of the file in `count` slices read in parallel, the first into this log, each
  // other into a log of its own, joined in file order: names mapped to the log's in the order
  // they first appear, line numbers counted on. Where the rows of one slice bear on another's
  // (a run's time going back across a boundary, a combination law's setup differing, the
  // limits on rows and names) the slices throw SlicesDisagree rather than decide.
  void read_slices(int count) {
    std::optional<csv::Reader::Rest> rest = reader_.read_rest(count);
    if (!rest) {  // being written: line by line
      read_rows();
      report_.bytes = static_cast<double>(reader_.bytes());
      return;
    }
    if (!column(kRun)) file_run_name();  // its note once, in this file's report
    struct Part {
      FrictionLog log;
      NameIndex runs{log.run_names}, guides{log.guide_names};
      std::unique_ptr<FileLoader> loader;
    };
    std::vector<std::unique_ptr<Part>> parts;
    const double rows_per_byte = static_cast<double>(reader_.estimated_rows()) /
                                 static_cast<double>(std::max<std::uintmax_t>(1, reader_.file_size()));
    for (std::size_t k = 0; k < rest->slices.size(); ++k) {
      auto& part = parts.emplace_back(std::make_unique<Part>());
      if (k == 0) {
        part->loader.reset(new FileLoader(*this, rest->slices[0], reader_.line(), log_, runs_, guides_));
        continue;
      }
      part->log.law = log_.law;
      part->loader.reset(new FileLoader(*this, rest->slices[k], 0, part->log, part->runs, part->guides));
      reserve(part->log, static_cast<std::size_t>(rows_per_byte * static_cast<double>(rest->slices[k].size())) + 16);
    }
    detail::for_each_slice(parts.size(), static_cast<int>(parts.size()), [&](int, std::size_t begin, std::size_t end) {
      for (std::size_t k = begin; k < end; ++k) parts[k]->loader->read_rows();
    });
    std::vector<LastSample> last = parts[0]->loader->last_;  // by the log's run index
    long lines_before = parts[0]->loader->reader_.line();
    for (std::size_t k = 0; k < parts.size(); ++k) {
      FileLoader& part = *parts[k]->loader;
      if (k != 0) {
        join(part, lines_before, last);
        lines_before += part.reader_.line();
      }
      report_.rows_read += part.report_.rows_read;
      skipped_ += part.skipped_;
      backward_rows_ += part.backward_rows_;
      negative_backward_ += part.negative_backward_;
      negative_rows_ += part.negative_rows_;
    }
    if (report_.rows_read > io::kMaxRows) throw SlicesDisagree();
    report_.bytes = static_cast<double>(reader_.file_size());
  }

  // The rows `part` read from a later slice appended to this file's (see read_slices); `last`:
  // each run's last sample so far, by the log's run index.
  void join(const FileLoader& part, long lines_before, std::vector<LastSample>& last) {
    const FrictionLog& from = part.log_;
    const std::vector<std::uint32_t> run_map = map_names<SlicesDisagree>(runs_, from.run_names);
    const std::vector<std::uint32_t> guide_map = map_names<SlicesDisagree>(guides_, from.guide_names);
    join_law(from.law);
    if (last.size() < runs_.size()) last.resize(runs_.size());
    for (std::size_t r = 0; r < part.last_.size(); ++r) {
      const LastSample& sample = part.last_[r];
      if (sample.line == 0) continue;
      LastSample& before = last[run_map[r]];
      if (sample.first_s < before.time_s) throw SlicesDisagree();
      before = {sample.time_s, sample.line + lines_before, before.line == 0 ? sample.first_s : before.first_s};
    }
    const auto append = [](auto& to, const auto& more) { to.insert(to.end(), more.begin(), more.end()); };
    for (std::uint32_t r : from.run) log_.run.push_back(run_map[r]);
    for (std::uint32_t g : from.guide) log_.guide.push_back(guide_map[g]);
    for (std::uint32_t l : from.line) log_.line.push_back(l + static_cast<std::uint32_t>(lines_before));
    append(log_.time_s, from.time_s);
    append(log_.velocity_m_s, from.velocity_m_s);
    append(log_.load_N, from.load_N);
    append(log_.preload_um, from.preload_um);
    append(log_.block_length_mm, from.block_length_mm);
    append(log_.temperature_C, from.temperature_C);
    append(log_.friction_N, from.friction_N);
    append(log_.viscosity40_mm2_s, from.viscosity40_mm2_s);
    append(log_.direction, from.direction);
    append(log_.acceleration_m_s2, from.acceleration_m_s2);
    append(log_.position_m, from.position_m);
    append(log_.distance_since_reversal_m, from.distance_since_reversal_m);
    append(log_.time_since_reversal_s, from.time_since_reversal_s);
  }

  // A combination law's setup as a later slice stated it (see law_conditions): the log's first
  // values, or SlicesDisagree.
  void join_law(const FrictionLawConditions& from) {
    FrictionLawConditions& law = log_.law;
    for (std::optional<double> FrictionLawConditions::*stated :
         {&FrictionLawConditions::load_N, &FrictionLawConditions::preload_um, &FrictionLawConditions::block_length_mm,
          &FrictionLawConditions::preload_N}) {
      if (!(from.*stated)) continue;
      if (!(law.*stated)) law.*stated = from.*stated;
      if (*(law.*stated) != *(from.*stated)) throw SlicesDisagree();
    }
    if (!law.preload_class) law.preload_class = from.preload_class;
  }

  const csv::Column* column(Spec spec) const { return bound_[spec]; }
  csv::Column* mutable_column(Spec spec) {
    for (csv::Column& c : columns_)
      if (c.spec == spec) return &c;
    return nullptr;
  }
  bool is_raw() const { return column(kForce) != nullptr; }

  [[noreturn]] void fail_header(const std::string& what) const { reader_.fail_at(reader_.header_line(), 1, what); }

  // A motor's speed or torque column becomes the carriage's velocity or force column: the
  // drive's factor (drive.hpp) folded into its unit conversion, its range the linear one's.
  void bind_drive() {
    const Drive& drive = raw_.drive;
    const auto linear = [&](Spec joint, Spec spec, Quantity quantity, double factor, const char* what,
                            const char* motor) {
      csv::Column* c = mutable_column(joint);
      if (!c) return;
      if (const csv::Column* other = csv::find_column(columns_, spec)) {
        const csv::Column* earlier = other->cell < c->cell ? other : c;
        const csv::Column* later = other->cell < c->cell ? c : other;
        reader_.fail(later->cell, fmt::format("'{}' gives the carriage's {} '{}' already gives: give one", later->header,
                                              what, earlier->header));
      }
      if (!drive.given()) {
        reader_.fail(c->cell, fmt::format("column '{}' is a motor's {}, not the carriage's {}: add a [drive] table to the "
                                          "friction manifest (lead_mm for a screw or pinion_radius_mm for a rack and "
                                          "pinion; gear_ratio, efficiency) or give --lead or --pinion-radius",
                                          c->header, motor, what));
      }
      const std::string unit = c->header.substr(c->name.size() + 1);
      if (is_relative_unit(*kSpecs[joint].quantity, unit)) {
        if (!drive.nominal_torque_Nm) {
          reader_.fail(c->cell, fmt::format("column '{}' is a share of the motor's nominal torque: add nominal_torque_Nm "
                                            "to the [drive] table (or give --nominal-torque)",
                                            c->header));
        }
        factor *= *drive.nominal_torque_Nm;
      }
      c->spec = spec;
      c->conversion.scale *= factor;
      c->range = physical_range(quantity);
      report_.conversions[c->header] =
          fmt::format("{} -> {} through the drive ({})", unit, unit_names(quantity).front(), drive.describe());
    };
    linear(kAngularVelocity, kVelocity, Quantity::velocity, drive.speed_per_motor_rad_s(), "velocity", "speed");
    const bool torque = csv::find_column(columns_, kTorque) != nullptr;
    linear(kTorque, kForce, Quantity::force, drive.force_per_motor_Nm(), "force", "torque");
    // The rotor's inertia is the drive's: in a motor's torque, not in a load cell's force.
    if (torque && drive.rotor_inertia_kg_m2 > 0) {
      const double reflected = drive.reflected_inertia_kg();
      report_.conversions["rotor_inertia_kg_m2"] = fmt::format(
          "{:g} kg·m² -> {:.6g} kg at the carriage, {}", drive.rotor_inertia_kg_m2, reflected,
          raw_.moving_mass_kg > 0 ? fmt::format("added to moving_mass_kg ({:g} kg) for the inertia taken off the force",
                                                raw_.moving_mass_kg)
                                  : std::string("part of the moving mass (not taken off the force: no moving_mass_kg)"));
      if (raw_.moving_mass_kg > 0) raw_.moving_mass_kg += reflected;
    }
  }

  // Which columns the file has decides its kind (tidy or raw) and what the manifest must give.
  void bind() {
    const bool raw = is_raw();
    if (raw && column(kFriction)) {
      reader_.fail(column(kForce)->cell, fmt::format("a log has '{}' (tidy: friction per sample) or '{}' (raw: the "
                                                     "load cell's signed force), not both",
                                                     column(kFriction)->header, column(kForce)->header));
    }
    if (!raw && !column(kFriction)) {
      fail_header(fmt::format("{}; or, for a raw load-cell log, a force column ({}) with time and position or velocity",
                              csv::missing_column(kSpecs[kFriction]), csv::accepted_names("force", Quantity::force)));
    }
    if (raw) {
      if (!column(kTime)) fail_header(fmt::format("a raw log ({}) needs a time column: {}", column(kForce)->header,
                                                  csv::accepted_names("time", Quantity::time)));
      if (const csv::Column* d = column(kDirection)) {
        reader_.fail(d->cell, fmt::format("a raw log ({}) takes the sense of motion from the motion itself; drop the "
                                          "'{}' column",
                                          column(kForce)->header, d->header));
      }
      if (column(kVelocity)) {
        motion_ = mutable_column(kVelocity);
        motion_->rule = Rule::any;  // signed in a raw log
        if (const csv::Column* p = column(kPosition)) report_.ignored_columns.push_back(p->header + " (velocity used)");
      } else if (column(kPosition)) {
        motion_ = mutable_column(kPosition);
        motion_kind_ = raw::Motion::position_m;
      } else {
        fail_header(fmt::format("a raw log ({}) needs the motion: a position column ({}) or a signed velocity ({})",
                                column(kForce)->header, csv::accepted_names("position", Quantity::distance_m),
                                csv::accepted_names("velocity", Quantity::velocity)));
      }
    } else {
      if (!column(kVelocity)) fail_header(csv::missing_column(kSpecs[kVelocity]));
      if (const csv::Column* p = column(kPosition)) report_.ignored_columns.push_back(p->header);
    }
    if (const csv::Column* a = column(kAcceleration); a && raw)
      report_.ignored_columns.push_back(a->header + " (a raw log's acceleration comes from its motion)");

    // The run: a column, or the manifest's name for the file; not both.
    if (column(kRun) && !file_.run.empty()) {
      reader_.fail(column(kRun)->cell, fmt::format("the manifest {} names this file's run ('{}'): drop the '{}' column "
                                                   "or the run's file key",
                                                   file_.manifest, file_.run, column(kRun)->header));
    }

    // Every condition from a column or the manifest, not both.
    for (const ConditionKey& key : kConditionKeys) check_given_once(key.spec, [&](const FrictionRunConditions& c) {
      return (c.*key.field).has_value() && !(key.spec == kBlockLength && c.block_length_from_catalog);
    });
    check_given_once(kGuide, [](const FrictionRunConditions& c) { return c.guide.has_value(); });
    check_given_once(kPreload, [](const FrictionRunConditions& c) { return c.preload_N || c.preload_class; });
    bind_law();
  }

  // Which of the law's conditions this file gives (a column, or a key of some run of the
  // manifest: then every run needs it); the log's files must agree.
  void bind_law() {
    const auto given = [&](Spec spec, std::optional<double> FrictionRunConditions::*field) {
      return column(spec) != nullptr ||
             std::any_of(file_.runs.begin(), file_.runs.end(), [&](const auto& run) { return (run.second.*field).has_value(); });
    };
    law_.load = given(kLoad, &FrictionRunConditions::load_N);
    law_.preload = given(kPreload, &FrictionRunConditions::preload_um);
    // A guide named for its block length that the catalog does not know meant to give it.
    law_.block_length = given(kBlockLength, &FrictionRunConditions::block_length_mm) ||
                        std::any_of(file_.runs.begin(), file_.runs.end(),
                                    [](const auto& run) { return !run.second.block_length_note.empty(); });
    law_.temperature = given(kTemperature, &FrictionRunConditions::temperature_C);
    if (law_.combination()) {
      report_.notes.push_back(fmt::format("not given: {}; the law is fitted in the combinations one setup determines (the "
                                          "Coulomb level, the Stribeck amplitude and speed, the viscous slope)",
                                          fmt::join(law_.not_logged(), ", ")));
    } else if (!law_.temperature) {
      report_.notes.push_back("not given: temperature_C; the law is evaluated at the oil's ν40 and β is not fitted");
    }
    if (log_.reports.empty()) {
      log_.law = law_;
      return;
    }
    const FrictionLawConditions& earlier = log_.law;
    if (earlier.load != law_.load || earlier.preload != law_.preload || earlier.block_length != law_.block_length ||
        earlier.temperature != law_.temperature) {
      fail_header(fmt::format("this file gives {} but {} gives {}: give the same conditions for every file of a log",
                              given_list(law_), log_.reports.front().file, given_list(earlier)));
    }
  }
  static std::string given_list(const FrictionLawConditions& law) {
    const std::vector<std::string> missing = law.not_logged();
    return missing.empty() ? std::string("every condition") : fmt::format("no {}", fmt::join(missing, ", "));
  }

  // The runs the manifest describes that rows of this file may belong to.
  template <typename Has>
  void check_given_once(Spec spec, Has has) const {
    const csv::Column* c = column(spec);
    if (!c) return;
    for (const auto& [id, conditions] : file_.runs) {
      if (has(conditions)) {
        reader_.fail(c->cell, fmt::format("'{}' is both a column of this file and a key of run '{}' in {}: give it "
                                          "once",
                                          c->header, id, file_.manifest));
      }
    }
  }


  // The manifest's conditions of run `run_index` (nullptr when it does not list the run);
  // a condition with neither column nor key is an error at the row's first run cell.
  const FrictionRunConditions* manifest_conditions(std::uint32_t run_index) {
    if (run_conditions_.size() <= run_index) run_conditions_.resize(run_index + 1, std::nullopt);
    auto& cached = run_conditions_[run_index];
    if (cached) return *cached;
    const std::string& name = log_.run_names[run_index];
    const FrictionRunConditions* found = nullptr;
    if (const auto it = file_.runs.find(name); it != file_.runs.end()) found = &it->second;
    for (const ConditionKey& key : kConditionKeys) {
      if (!key.required || !logged(key.spec) || column(key.spec) || (found && (found->*key.field))) continue;
      std::string what =
          fmt::format("run '{}' has no {}: add {} to its [[run]] in {}, or a '{}' column to this file", name,
                      header_of(key.spec), header_of(key.spec), file_.manifest, header_of(key.spec));
      if (key.spec == kBlockLength && found && !found->block_length_note.empty())
        what += fmt::format(" ({})", found->block_length_note);
      if (column(kRun)) reader_.fail(column(kRun)->cell, what);
      reader_.fail_at(reader_.line(), 0, what);
    }
    cached = found;
    return found;
  }

  // Without a guide column, a run's guide is the manifest's (or none): looked up once per run.
  std::uint32_t run_guide(std::uint32_t run_index, const FrictionRunConditions* given) {
    if (run_guide_.size() <= run_index) run_guide_.resize(run_index + 1, std::nullopt);
    auto& cached = run_guide_[run_index];
    if (!cached) cached = guides_(given && given->guide ? std::string_view(*given->guide) : std::string_view());
    return *cached;
  }

  // A condition of the current row: its column, else the manifest's value, else `fallback`.
  double condition(Spec spec, std::optional<double> FrictionRunConditions::*field, const FrictionRunConditions* c,
                   double fallback = 0) const {
    if (const csv::Column* col = column(spec)) return reader_.number(*col, false);
    return c && (c->*field) ? *(c->*field) : fallback;
  }

  // The index of a run or guide name; a name seen for the first time is checked (UTF-8,
  // printable) and counted against the limit.
  std::uint32_t name_index(NameIndex& names, const csv::Column& column, std::string_view name, std::string_view what) {
    const std::size_t known = names.size();
    const std::uint32_t index = names(name);
    if (names.size() != known) {
      if (auto problem = io::name_problem(name)) reader_.fail(column.cell, fmt::format("{} name: {}", what, *problem));
      if (names.size() > io::kMaxRuns) {
        reader_.fail(column.cell, fmt::format("more than {} {}s in one data set (the limit, docs/formats.md#limits)",
                                              io::kMaxRuns, what));
      }
    }
    return index;
  }

  // The run of a file without a run column: the manifest's, or one named after the file.
  const std::string& file_run_name() {
    if (!file_run_name_) file_run_name_ = file_.run.empty() ? default_run_name() : file_.run;
    return *file_run_name_;
  }

  // A file without a run column or a manifest's run: one run, named after the file.
  std::string default_run_name() {
    std::string name = file_.path.stem().string();
    if (auto problem = io::name_problem(name)) fail_header(fmt::format("no run column, and the file's name cannot name its run: {}", *problem));
    report_.notes.push_back(fmt::format("no run column: one run, named '{}' after the file", name));
    return name;
  }

  bool logged(Spec spec) const {
    switch (spec) {
      case kLoad: return law_.load;
      case kPreload: return law_.preload;
      case kBlockLength: return law_.block_length;
      case kTemperature: return law_.temperature;
      default: return true;
    }
  }

  // A row's conditions as the law sees them: a combination law's at the neutral values (each
  // stated one checked to be the log's one setup), an unlogged temperature at T_i.
  FrictionConditions<double> law_conditions(FrictionConditions<double> c, const FrictionRunConditions* given) {
    using Law = FrictionLawConditions;
    if (!law_.temperature) c.temperature_C = Law::kUnloggedTemperature_C;
    if (!law_.combination()) return c;
    FrictionLawConditions& law = log_.law;
    const auto one_setup = [&](const std::string& name, const csv::Column* col, bool is_logged, double value,
                               std::optional<double> Law::*stated) {
      if (!is_logged) return;
      if (!(law.*stated)) {
        law.*stated = value;
      } else if (*(law.*stated) != value) {
        const std::string what = fmt::format(
            "{} = {} differs from the log's first value, {}: without {} the law is fitted in the combinations of "
            "one setup; give {} for the paper's scalings, or fit each setup as its own log",
            name, value, *(law.*stated), fmt::join(law.not_logged(), ", "), fmt::join(law.not_logged(), ", "));
        if (col) reader_.fail(col->cell, what);
        reader_.fail_at(reader_.line(), 0, what + fmt::format(" (the value of run '{}' in {})", log_.run_names.at(last_run_),
                                                               file_.manifest));
      }
    };
    one_setup(header_of(kLoad), column(kLoad), law_.load, c.load_N, &Law::load_N);
    one_setup(header_of(kPreload), column(kPreload), law_.preload, c.preload_um, &Law::preload_um);
    one_setup(header_of(kBlockLength), column(kBlockLength), law_.block_length, c.block_length_mm, &Law::block_length_mm);
    if (given && given->preload_N) one_setup("preload_N", nullptr, true, *given->preload_N, &Law::preload_N);
    if (given && given->preload_class && !law.preload_class) law.preload_class = given->preload_class;
    c.load_N = Law::kNeutralLoad_N;
    c.preload_um = Law::kNeutralPreload_um;
    c.block_length_mm = Law::kNeutralBlockLength_mm;
    return c;
  }

  void read_row(std::string& scratch) {
    if (!column(kRun) && !file_run_) file_run_ = runs_(file_run_name());
    const std::uint32_t run_index =
        column(kRun) ? name_index(runs_, *column(kRun), name_cell(reader_, *column(kRun), scratch), "run") : *file_run_;
    const FrictionRunConditions* given = manifest_conditions(run_index);
    // An empty guide cell: the run's guide from the manifest, or none (a log lmcal writes for
    // samples of which only some name a guide).
    const std::string_view guide = column(kGuide) ? reader_.text(column(kGuide)->cell, scratch) : std::string_view();
    const std::uint32_t guide_index =
        guide.empty() ? run_guide(run_index, given) : name_index(guides_, *column(kGuide), guide, "guide");
    const double t = column(kTime) ? reader_.number(*column(kTime), false) : kNaN;
    last_run_ = run_index;
    const FrictionConditions<double> c = law_conditions(
        {.load_N = condition(kLoad, &FrictionRunConditions::load_N, given),
         .preload_um = condition(kPreload, &FrictionRunConditions::preload_um, given),
         .block_length_mm = condition(kBlockLength, &FrictionRunConditions::block_length_mm, given),
         .temperature_C = condition(kTemperature, &FrictionRunConditions::temperature_C, given)},
        given);
    const double nu40 =
        condition(kViscosity40, &FrictionRunConditions::viscosity40_mm2_s, given, kDefaultViscosity40_mm2_s);
    if (is_raw()) {
      read_raw_row(run_index, guide_index, t, c, nu40);
      return;
    }
    const double v = reader_.number(*column(kVelocity), false);
    const double f = reader_.number(*column(kFriction), true);
    const double dir = column(kDirection) ? reader_.number(*column(kDirection), false) : 1.0;
    if (column(kTime)) check_time_order(run_index, t, false);
    // The rest of the row was checked: a missing friction value only skips the sample.
    if (std::isnan(f)) {
      ++skipped_;
      return;
    }
    FrictionConditions<double> sample = c;
    sample.velocity_m_s = v;
    sample.direction = dir;
    if (const csv::Column* a = column(kAcceleration)) sample.acceleration_m_s2 = reader_.number(*a, false);
    log_.append(run_index, guide_index, t, sample, f, nu40, static_cast<std::uint32_t>(reader_.line()));
    if (dir < 0) {
      ++backward_rows_;
      negative_backward_ += f < 0;
    }
    negative_rows_ += f < 0;
  }

  // Time must not decrease within a run (within this file); a raw log's repeated time is
  // refused or merged (returns true: merge into the previous sample).
  bool check_time_order(std::uint32_t run_index, double t, bool raw) {
    if (last_.size() <= run_index) last_.resize(run_index + 1);
    LastSample& previous = last_[run_index];
    const csv::Column& time = *column(kTime);
    if (t < previous.time_s) {
      reader_.fail(time.cell, fmt::format("{} = {} is earlier than the previous sample of run '{}' (line {}); time "
                                          "must not decrease within a run",
                                          time.header, reader_.cell(time.cell), log_.run_names[run_index],
                                          previous.line));
    }
    if (raw && t == previous.time_s) {
      if (raw_.duplicate_times == DuplicateTimes::refuse) {
        reader_.fail(time.cell, fmt::format("{} = {} repeats the time of the previous sample of run '{}' (line {}); "
                                            "refused as asked (duplicate_times = refuse); the default, average, "
                                            "merges such samples into one",
                                            time.header, reader_.cell(time.cell), log_.run_names[run_index],
                                            previous.line));
      }
      return true;
    }
    previous = {t, reader_.line(), previous.line == 0 ? t : previous.first_s};
    return false;
  }

  void read_raw_row(std::uint32_t run_index, std::uint32_t guide_index, double t, const FrictionConditions<double>& c,
                    double nu40) {
    const double motion = reader_.number(*motion_, false);
    const double force = reader_.number(*column(kForce), true);
    if (std::isnan(force)) {
      ++skipped_;
      return;
    }
    const bool merge = check_time_order(run_index, t, true);
    if (raw_index_.size() <= run_index) raw_index_.resize(run_index + 1, kNone);
    if (raw_index_[run_index] == kNone) {
      raw_index_[run_index] = raw_runs_.size();
      raw_runs_.push_back({.run = run_index});
      if (raw_runs_.size() == 1) raw_runs_.back().reserve(reader_.estimated_rows());  // most raw files hold one run
    }
    RawRun& r = raw_runs_[raw_index_[run_index]];
    if (merge && !r.line.empty()) {
      const double k = r.last_merged;
      r.samples.motion.back() = (r.samples.motion.back() * k + motion) / (k + 1);
      r.samples.force_N.back() = (r.samples.force_N.back() * k + force) / (k + 1);
      ++r.last_merged;
      ++r.merged;
      ++merged_;
      return;
    }
    r.samples.time_s.push_back(t);
    r.samples.motion.push_back(motion);
    r.samples.force_N.push_back(force);
    r.line.push_back(reader_.line());
    r.last_merged = 1;
    r.add_setup({guide_index, c, nu40});
  }

  // Each raw run cut into plateaus; the kept samples go into the log.
  void segment_raw_runs() {
    RunSegmentation total;
    for (RawRun& r : raw_runs_) {
      const std::string& name = log_.run_names[r.run];
      raw::Segmented s;
      try {
        s = raw::segment(r.samples, motion_kind_, raw_);
      } catch (const raw::SampleError& e) {
        csv::fail_at_cell(file_.path, r.line[e.sample], motion_->cell, fmt::format("run '{}': {}", name, e.what()));
      }
      RunSegmentation seg{.run = name, .file = report_.file};
      raw::tally(s, seg);
      seg.averaged_duplicates = r.merged;
      // On an inclined axis the drive holds the weight: its force may keep one sign both ways.
      if (!(s.trajectory() && raw_.axis_incline_deg != 0))
        for (const std::string& w : raw::sign_warnings(name, column(kForce)->header, r.samples, s, raw_))
          report_.warnings.push_back(w);
      if (!s.trajectory() && 3 * seg.kept < 2 * seg.samples)
        report_.warnings.push_back(fmt::format(
            "run '{}': the plateau reader kept {} of {} samples ({:.0f} %): a drive's log that never holds a speed is "
            "read whole with --segmentation trajectory (segmentation = \"trajectory\" in the manifest's [raw]), which "
            "fits the moving mass with the law; or shorten --settling ({} s)",
            name, seg.kept, seg.samples, 100.0 * static_cast<double>(seg.kept) / static_cast<double>(std::max<std::size_t>(seg.samples, 1)),
            raw_.settling_s));
      const raw::Travel travel = raw::travel(r.samples, motion_kind_, s, raw_);
      for (std::size_t i = 0; i < s.fate.size(); ++i) {
        if (s.fate[i] != raw::Fate::kept) continue;
        // A plateau's sample takes its plateau's speed; a trajectory's, its own filtered one.
        const double v = s.trajectory() ? s.velocity_m_s[i] : s.plateaus[s.plateau[i]].velocity_m_s;
        // A plateau's speed comes from positions over time: held to the range a column's is.
        if (const PhysicalRange range = physical_range(Quantity::velocity); !range.contains(v)) {
          csv::fail_at_cell(file_.path, r.line[i], motion_->cell,
                            fmt::format("run '{}': {}", name,
                                        out_of_range_message("the plateau's velocity_m_s", fmt::format("{:g}", v), range)));
        }
        const SampleSetup& setup = r.setups[r.setup[i]];
        FrictionConditions<double> c = setup.conditions;
        c.velocity_m_s = std::abs(v);
        c.direction = v < 0 ? -1.0 : 1.0;
        c.acceleration_m_s2 = s.trajectory() ? s.acceleration_m_s2[i] : 0.0;
        c.position_m = travel.position_m[i];
        c.distance_since_reversal_m = travel.distance_since_reversal_m[i];
        log_.append(r.run, setup.guide, r.samples.time_s[i], c, raw::friction_N(r.samples, s, raw_, i),
                    setup.viscosity40, static_cast<std::uint32_t>(r.line[i]));
        log_.time_since_reversal_s.back() = travel.time_since_reversal_s[i];
      }
      log_.raw_traces.push_back(thin_trace(name, r.samples, s));
      total.kept += seg.kept;
      total.dropped_acceleration += seg.dropped_acceleration;
      total.dropped_settling += seg.dropped_settling;
      total.dropped_stationary += seg.dropped_stationary;
      total.dropped_short += seg.dropped_short;
      log_.segmentation.push_back(std::move(seg));
    }
    const auto skip = [&](std::size_t count, const std::string& reason) {
      if (count != 0) report_.skipped[reason] = count;
    };
    skip(skipped_, column(kForce)->header + " empty or NaN");
    skip(merged_, "merged into a sample at the same time");
    skip(total.dropped_acceleration,
         raw_.segmentation == RawSegmentation::trajectory
             ? std::string("at a step of the drive force (a jump 5 σ out of its trend, or within the filter's reach of "
                           "one: where in the sample interval it fell is unknown)")
             : fmt::format("accelerating (|a| > {} m/s²)", raw_.max_acceleration_m_s2));
    if (raw_.segmentation == RawSegmentation::trajectory) {
      log_.trajectory = true;
      log_.axis_incline_deg = raw_.axis_incline_deg;
      skip(total.dropped_stationary, "at rest or reversing (slower than max(min_speed, 3 σ_v), or within the filter's "
                                     "reach of such a sample: static friction, not the sliding law) or within the "
                                     "filter's reach of the log's ends (a window cut short)");
      skip(total.dropped_settling, fmt::format("pre-sliding (the first {} mm of travel after rest or a reversal)",
                                               raw_.presliding_m * 1e3));
    } else {
      skip(total.dropped_settling, fmt::format("settling ({} s after an acceleration)", raw_.settling_s));
      skip(total.dropped_stationary, fmt::format("at rest (speed < {} m/s)", raw_.min_speed_m_s));
    }
    skip(total.dropped_short, fmt::format("in plateaus shorter than {} samples", raw_.min_plateau_samples));
    report_.rows_kept = total.kept;
  }

  static RawTrace thin_trace(const std::string& run, const raw::RunSamples& samples, const raw::Segmented& s) {
    RawTrace trace{.run = run};
    const std::size_t n = samples.time_s.size();
    const std::size_t stride = std::max<std::size_t>(1, (n + RawTrace::kMaxPoints - 1) / RawTrace::kMaxPoints);
    for (std::size_t i = 0; i < n; i += stride) {
      trace.time_s.push_back(samples.time_s[i]);
      trace.velocity_m_s.push_back(s.velocity_m_s[i]);
      trace.force_N.push_back(samples.force_N[i]);
    }
    return trace;
  }

  // A tidy log's friction is a magnitude; negative values where the block moves backwards
  // are a signed force given in the wrong column.
  void warn_signed_friction() {
    const std::string& header = column(kFriction)->header;
    if (backward_rows_ != 0 && 2 * negative_backward_ >= backward_rows_) {
      report_.warnings.push_back(fmt::format(
          "{} is negative on {} of the {} samples with direction = -1: a tidy log's friction is a magnitude (the "
          "direction column gives the sense); take its absolute value, or give the signed force as a raw log "
          "(force_N with time_s and position_mm or velocity_m_s)",
          header, negative_backward_, backward_rows_));
    } else if (!column(kDirection) && 4 * negative_rows_ >= log_.size() && negative_rows_ != 0) {
      report_.warnings.push_back(fmt::format(
          "{} is negative on {} of the {} samples: a tidy log's friction is a magnitude; for a signed force, give a "
          "direction column and the magnitude, or a raw log (force_N with time_s and position_mm or velocity_m_s)",
          header, negative_rows_, report_.rows_read));
    }
  }


  const detail::FrictionFile& file_;
  RawFrictionOptions raw_;  // the moving mass with the rotor's reflected inertia (bind_drive)
  FrictionLog& log_;
  NameIndex& runs_;
  NameIndex& guides_;
  csv::Reader reader_;
  LoadReport report_;
  std::vector<csv::Column> columns_;
  std::array<const csv::Column*, kSpecs.size()> bound_{};  // by spec: its column, or nullptr
  csv::Column* motion_ = nullptr;  // a raw log's position or velocity
  std::optional<std::uint32_t> file_run_;  // the manifest's run of a file without a run column
  std::optional<std::string> file_run_name_;  // its name, once asked for
  FrictionLawConditions law_;              // what this file gives
  std::uint32_t last_run_ = 0;             // the current row's run
  raw::Motion motion_kind_ = raw::Motion::velocity_m_s;
  std::vector<std::optional<const FrictionRunConditions*>> run_conditions_;  // by run index, once looked up
  std::vector<std::optional<std::uint32_t>> run_guide_;                      // by run index, without a guide column
  std::vector<LastSample> last_;                                             // by run index
  std::vector<std::size_t> raw_index_;                                       // run index -> raw_runs_
  std::vector<RawRun> raw_runs_;
  std::size_t skipped_ = 0, merged_ = 0;
  std::size_t backward_rows_ = 0, negative_backward_ = 0, negative_rows_ = 0;
};

}  // namespace

std::string_view to_string(ForceSensor s) {
  switch (s) {
    case ForceSensor::load_cell: return "load_cell";
    case ForceSensor::motor_current: return "motor_current";
    case ForceSensor::torque_sensor: return "torque_sensor";
    case ForceSensor::unknown: break;
  }
  return "unknown";
}

ForceSensor parse_force_sensor(std::string_view name) {
  for (ForceSensor s : {ForceSensor::unknown, ForceSensor::load_cell, ForceSensor::motor_current, ForceSensor::torque_sensor})
    if (name == to_string(s)) return s;
  throw InvalidParameter("force_sensor", fmt::format("unknown sensor '{}': expected load_cell, motor_current, "
                                                     "torque_sensor or unknown",
                                                     name));
}

std::vector<std::string> FrictionLawConditions::not_logged() const {
  std::vector<std::string> out;
  if (!load) out.push_back(header_of(kLoad));
  if (!preload) out.push_back(preload_N ? header_of(kPreload) + " (only preload_N)" : header_of(kPreload));
  if (!block_length) out.push_back(header_of(kBlockLength));
  if (!temperature) out.push_back(header_of(kTemperature));
  return out;
}

std::string FrictionLawConditions::stated() const {
  std::vector<std::string> parts;
  if (load_N) parts.push_back(fmt::format("load {:g} N", *load_N));
  if (preload_um) {
    parts.push_back(preload_class ? fmt::format("preload {:g} µm (class {})", *preload_um, *preload_class)
                                  : fmt::format("preload {:g} µm", *preload_um));
  }
  if (preload_N) parts.push_back(fmt::format("preload {:g} N", *preload_N));
  if (block_length_mm) parts.push_back(fmt::format("block length {:g} mm", *block_length_mm));
  return parts.empty() ? std::string("no conditions given") : fmt::format("{}", fmt::join(parts, ", "));
}

double preload_class_um(std::string_view preload_class, std::string_view guide) {
  // The middle of each class's radial clearance, −µm (PHYSICS.md §1a; size 25's C0 is −4…−3).
  const bool size25 = guide.find(" 25") != std::string_view::npos;
  if (preload_class == "normal") return 1.5;
  if (preload_class == "C1") return 2.5;
  if (preload_class == "C0") return size25 ? 3.5 : 4.0;
  throw InvalidParameter("preload_class", fmt::format("unknown class '{}': expected normal, C1 or C0 (THK SRG/SRN)",
                                                      preload_class));
}

FrictionConditions<double> FrictionLog::conditions(std::size_t i) const {
  return {.load_N = load_N[i],
          .preload_um = preload_um[i],
          .block_length_mm = block_length_mm[i],
          .velocity_m_s = velocity_m_s[i],
          .temperature_C = temperature_C[i],
          .direction = static_cast<double>(direction[i]),
          .acceleration_m_s2 = i < acceleration_m_s2.size() ? acceleration_m_s2[i] : 0.0,
          .position_m = i < position_m.size() ? position_m[i] : 0.0,
          .distance_since_reversal_m = i < distance_since_reversal_m.size() ? distance_since_reversal_m[i] : 0.0};
}

// Flattened: sixteen push_backs inlined (their capacity reserved by the loaders) rather than called.
[[gnu::flatten]] void FrictionLog::append(std::uint32_t run_index, std::uint32_t guide_index, double time,
                         const FrictionConditions<double>& c, double friction, double viscosity40,
                         std::uint32_t source_line) {
  run.push_back(run_index);
  guide.push_back(guide_index);
  time_s.push_back(time);
  velocity_m_s.push_back(c.velocity_m_s);
  load_N.push_back(c.load_N);
  preload_um.push_back(c.preload_um);
  block_length_mm.push_back(c.block_length_mm);
  temperature_C.push_back(c.temperature_C);
  friction_N.push_back(friction);
  viscosity40_mm2_s.push_back(viscosity40);
  direction.push_back(static_cast<std::int8_t>(c.direction));
  acceleration_m_s2.push_back(c.acceleration_m_s2);
  position_m.push_back(c.position_m);
  distance_since_reversal_m.push_back(c.distance_since_reversal_m);
  time_since_reversal_s.push_back(std::numeric_limits<double>::quiet_NaN());
  line.push_back(source_line);
}

FrictionLog load_friction_log(const fs::path& file, const RawFrictionOptions& raw) {
  return load_friction_logs({file}, raw);
}

FrictionLog load_friction_logs(const std::vector<fs::path>& files, const RawFrictionOptions& raw) {
  std::vector<detail::FrictionFile> list;
  for (const fs::path& file : files) list.push_back({.path = file});
  return detail::load_friction_files(list, raw);
}

namespace detail {

namespace {

// Thrown where files read apart bear on each other (read_files_apart): the files are then read
// one after the other, which says what and where.
struct FilesDisagree : std::exception {
  const char* what() const noexcept override { return "the files of a log read apart disagree"; }
};

// `part`, one file read into a log of its own, appended to `log` as reading it after the files
// before would have: its run and guide names mapped to the log's in the order they first
// appear, its report, runs' segmentation and traces after the others'. Where that reading
// would have refused the file (what it gives of the law's conditions differs; the limit on
// names), FilesDisagree.
void append_file(FrictionLog& log, NameIndex& runs, NameIndex& guides, const FrictionLog& part) {
  const std::vector<std::uint32_t> run_map = map_names<FilesDisagree>(runs, part.run_names);
  const std::vector<std::uint32_t> guide_map = map_names<FilesDisagree>(guides, part.guide_names);
  FrictionLawConditions& law = log.law;
  if (log.reports.empty()) {
    law = part.law;
  } else {
    const FrictionLawConditions& given = part.law;
    if (law.load != given.load || law.preload != given.preload || law.block_length != given.block_length ||
        law.temperature != given.temperature)
      throw FilesDisagree();
    for (std::optional<double> FrictionLawConditions::*stated :
         {&FrictionLawConditions::load_N, &FrictionLawConditions::preload_um, &FrictionLawConditions::block_length_mm,
          &FrictionLawConditions::preload_N}) {
      if (!(given.*stated)) continue;
      if (!(law.*stated)) law.*stated = given.*stated;
      if (*(law.*stated) != *(given.*stated)) throw FilesDisagree();
    }
    if (!law.preload_class) law.preload_class = given.preload_class;
  }
  const auto append = [](auto& to, const auto& more) { to.insert(to.end(), more.begin(), more.end()); };
  for (std::uint32_t r : part.run) log.run.push_back(run_map[r]);
  for (std::uint32_t g : part.guide) log.guide.push_back(guide_map[g]);
  append(log.time_s, part.time_s);
  append(log.velocity_m_s, part.velocity_m_s);
  append(log.load_N, part.load_N);
  append(log.preload_um, part.preload_um);
  append(log.block_length_mm, part.block_length_mm);
  append(log.temperature_C, part.temperature_C);
  append(log.friction_N, part.friction_N);
  append(log.viscosity40_mm2_s, part.viscosity40_mm2_s);
  append(log.direction, part.direction);
  append(log.acceleration_m_s2, part.acceleration_m_s2);
  append(log.position_m, part.position_m);
  append(log.distance_since_reversal_m, part.distance_since_reversal_m);
  append(log.time_since_reversal_s, part.time_since_reversal_s);
  append(log.line, part.line);
  append(log.reports, part.reports);
  append(log.segmentation, part.segmentation);
  append(log.raw_traces, part.raw_traces);
  if (part.trajectory) {
    log.trajectory = true;
    log.axis_incline_deg = part.axis_incline_deg;
  }
}

// Several files, each read (parsed, and a raw file's runs segmented) on a free thread into a log
// of its own, then appended in file order (append_file): the log reading them one after the
// other gives, the same bits. A 10⁶-sample trajectory in three raw files loaded in 2/3 of the
// time on two cores. Null where it cannot decide (a file refused, files that bear on each
// other): the caller reads them one after the other.
std::optional<FrictionLog> read_files_apart(const std::vector<FrictionFile>& files, const RawFrictionOptions& raw) {
  std::vector<FrictionLog> parts(files.size());
  try {
    for_each_index(files.size(), [&](std::size_t k) {
      NameIndex runs(parts[k].run_names), guides(parts[k].guide_names);
      FileLoader(files[k], raw, parts[k], runs, guides).load(nullptr);
    });
  } catch (const std::exception&) {
    return std::nullopt;
  }
  FrictionLog log;
  log.force_sensor = raw.force_sensor;
  log.incline_stated = raw.incline_stated;
  std::size_t total = 0;
  for (const FrictionLog& part : parts) total += part.size();
  FileLoader::reserve(log, total);
  NameIndex runs(log.run_names), guides(log.guide_names);
  try {
    for (const FrictionLog& part : parts) append_file(log, runs, guides, part);
  } catch (const FilesDisagree&) {
    return std::nullopt;
  }
  return log;
}

}  // namespace

FrictionLog load_friction_files(const std::vector<FrictionFile>& files, const RawFrictionOptions& raw) {
  raw.validate();
  if (files.size() >= 2 && slice_threads(files.size(), 1) > 1)
    if (std::optional<FrictionLog> log = read_files_apart(files, raw)) return std::move(*log);
  const auto read = [&](bool* sliced) {
    FrictionLog log;
    log.force_sensor = raw.force_sensor;
    log.incline_stated = raw.incline_stated;
    NameIndex runs(log.run_names);
    NameIndex guides(log.guide_names);
    for (const FrictionFile& file : files) FileLoader(file, raw, log, runs, guides).load(sliced);
    return log;
  };
  // Large files are read in slices in parallel; when that throws (a bad row, slices that
  // disagree), the files are read again line by line, which says what and where as it always did.
  bool sliced = false;
  try {
    return read(&sliced);
  } catch (const std::exception&) {
    if (!sliced) throw;
  }
  return read(nullptr);
}

}  // namespace detail

std::string friction_log_csv(const FrictionLog& log, const std::vector<std::string>& comments) {
  // Optional columns are written when they carry information: guide when a sample names
  // one, time when every sample has one (a NaN time would not load back).
  const bool with_guide =
      std::any_of(log.guide_names.begin(), log.guide_names.end(), [](const std::string& g) { return !g.empty(); });
  const bool with_time =
      log.size() != 0 && std::none_of(log.time_s.begin(), log.time_s.end(), [](double t) { return std::isnan(t); });
  // The acceleration when a sample has one (a moving mass's error shows against it).
  const bool with_acceleration =
      std::any_of(log.acceleration_m_s2.begin(), log.acceleration_m_s2.end(), [](double a) { return a != 0; });

  std::vector<std::string> header{header_of(kRun)};
  if (with_guide) header.push_back(header_of(kGuide));
  if (with_time) header.push_back(header_of(kTime));
  for (Spec spec : {kVelocity, kLoad, kPreload, kBlockLength, kTemperature, kFriction, kViscosity40, kDirection}) {
    header.push_back(header_of(spec));
  }
  if (with_acceleration) header.push_back(header_of(kAcceleration));

  CsvText csv(header, comments);
  for (std::size_t i = 0; i < log.size(); ++i) {
    csv.cell(log.run_names.at(log.run[i]));
    if (with_guide) csv.cell(log.guide_names.at(log.guide[i]));
    if (with_time) csv.cell(log.time_s[i]);
    csv.cell(log.velocity_m_s[i])
        .cell(log.load_N[i])
        .cell(log.preload_um[i])
        .cell(log.block_length_mm[i])
        .cell(log.temperature_C[i])
        .cell(log.friction_N[i])
        .cell(log.viscosity40_mm2_s[i])
        .cell(static_cast<double>(log.direction[i]));
    if (with_acceleration) csv.cell(log.acceleration_m_s2[i]);
    csv.end_row();
  }
  return csv.str();
}

}  // namespace lmcal
