// One friction-log file read: its header bound to the log's columns (a drive's motor columns
// folded into the carriage's), the law's conditions it gives, and its rows read and checked.
#include "friction_file_loader.hpp"

#include <fmt/ranges.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <tuple>

#include "io/input_file.hpp"
#include "parallel_slices.hpp"
#include "lmcal/error.hpp"

namespace lmcal::detail::friction_reading {

// The text of a run or guide cell; an empty name is an error.
std::string_view name_cell(const csv::Reader& reader, const csv::Column& column, std::string& scratch) {
  const std::string_view name = reader.text(column.cell, scratch);
  if (name.empty())
    reader.fail(column.cell, fmt::format("column '{}': expected a name, found an empty cell", column.header));
  return name;
}

FileLoader::FileLoader(const detail::FrictionFile& file, const RawFrictionOptions& raw, FrictionLog& log, NameIndex& runs,
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

void FileLoader::load(bool* sliced) {
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

void FileLoader::reserve(FrictionLog& log, std::size_t capacity) {
  // Each column's storage mapped on a free thread (a million rows: 8 MB a column).
  std::vector<std::function<void()>> columns;
  const auto each = [&](auto... member) {
    (columns.emplace_back([&log, capacity, member] { csv::reserve_rows(log.*member, capacity); }), ...);
  };
  std::apply(each, kValueColumns);
  std::apply(each, kIndexColumns);
  constexpr std::size_t kParallelRows = 1 << 16;
  if (capacity < kParallelRows) {
    for (const auto& column : columns) column();
    return;
  }
  detail::for_each_index(columns.size(), [&](std::size_t c) { columns[c](); });
}

void FileLoader::read_rows() {
  std::string scratch;
  while (reader_.next()) {
    ++report_.rows_read;
    read_row(scratch);
  }
}

void FileLoader::bind_drive() {
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

void FileLoader::bind() {
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

void FileLoader::bind_law() {
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

const FrictionRunConditions* FileLoader::manifest_conditions(std::uint32_t run_index) {
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

std::uint32_t FileLoader::run_guide(std::uint32_t run_index, const FrictionRunConditions* given) {
  if (run_guide_.size() <= run_index) run_guide_.resize(run_index + 1, std::nullopt);
  auto& cached = run_guide_[run_index];
  if (!cached) cached = guides_(given && given->guide ? std::string_view(*given->guide) : std::string_view());
  return *cached;
}

std::uint32_t FileLoader::name_index(NameIndex& names, const csv::Column& column, std::string_view name, std::string_view what) {
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

std::string FileLoader::default_run_name() {
  std::string name = file_.path.stem().string();
  if (auto problem = io::name_problem(name)) fail_header(fmt::format("no run column, and the file's name cannot name its run: {}", *problem));
  report_.notes.push_back(fmt::format("no run column: one run, named '{}' after the file", name));
  return name;
}

bool FileLoader::logged(Spec spec) const {
  switch (spec) {
    case kLoad: return law_.load;
    case kPreload: return law_.preload;
    case kBlockLength: return law_.block_length;
    case kTemperature: return law_.temperature;
    default: return true;
  }
}

FrictionConditions<double> FileLoader::law_conditions(FrictionConditions<double> c, const FrictionRunConditions* given) {
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

void FileLoader::read_row(std::string& scratch) {
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

bool FileLoader::check_time_order(std::uint32_t run_index, double t, bool raw) {
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

void FileLoader::warn_signed_friction() {
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

}  // namespace lmcal::detail::friction_reading
