// Friction logs: tidy CSV from a load-cell rig, one row per sample.
//
// Required columns (any accepted unit, see units.hpp): velocity_m_s and friction_N.
// Optional: run (default: one run named after the file), load_N, preload_um, block_length_mm,
// temperature_C (FrictionLawConditions: what is not given is not invented), time_s,
// viscosity40_mm2_s (default 99), direction (+1/-1, default +1), guide.
// Lines starting with '#' are comments. Columns lmcal does not know are ignored and
// listed in the report; a known quantity with an unknown unit is an error.
//
// Rules: velocity is a speed (>= 0; the direction column gives the sense), load and
// preload >= 0, block length > 0, temperature above absolute zero, time (if present)
// non-decreasing within a run. An empty or NaN friction cell skips the row and is
// counted in report.skipped; any other empty, NaN or non-numeric cell is an error.
//
// Bad input throws InputError(file, line, column, what was expected) before anything
// is returned; the column is the 1-based character position of the offending cell.
//
// Raw load-cell time series. A log with a `force` column (any force unit) instead of
// `friction` is a rig's raw record: `time` plus `position` (any distance unit; the velocity
// is derived from it) or a signed `velocity`, and the force as the load cell gave it, signed.
// Such a log is cut into constant-velocity plateaus (segment_raw_run below): samples while the
// block accelerates (|a| above a threshold), for a settling time after it, at rest, and in
// plateaus too short to trust are dropped; a kept sample takes its plateau's mean velocity
// (sense in `direction`) and its friction is the force with the sign convention applied and
// the inertia m·a taken off. `direction` is not a column of a raw log (the motion gives it).
// FrictionLog::segmentation says, per run, what was kept and dropped.
//
// Run conditions without columns: a run's load, preload, block length, guide, temperature and
// ν40 may come from a friction manifest (load_friction_dataset) instead of columns; a
// quantity given both ways is refused.
//
// Example:
//   auto log = lmcal::load_friction_log("measurements/friction/srn35c.csv");
//   for (std::size_t i = 0; i < log.size(); ++i) use(log.conditions(i), log.friction_N[i]);
#pragma once

#include "lmcal/export.hpp"

#include <cstdint>
#include <filesystem>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "lmcal/io/catalog.hpp"
#include "lmcal/io/drive.hpp"
#include "lmcal/io/friction_conditions.hpp"
#include "lmcal/io/input_scope.hpp"
#include "lmcal/io/load_report.hpp"

namespace LMCAL_API lmcal {

// How a raw log's signed force relates to friction. `follows_motion`: the force is positive
// while the block moves towards +x (the drive's pull, what an in-line load cell reads);
// `opposes_motion`: the reverse (a cell mounted the other way round); `magnitude`: the force is
// already unsigned. The direction always comes from the motion.
enum class ForceSign { follows_motion, opposes_motion, magnitude };
std::string_view to_string(ForceSign sign);
// "follows-motion", "opposes-motion", "magnitude"; InvalidParameter otherwise.
ForceSign parse_force_sign(std::string_view name);

// How a raw log is read: cut into constant-velocity plateaus (a friction rig's log), or kept
// whole as a trajectory (a drive's own log: closed-loop moves that never hold a speed), every
// sample in motion kept with its filtered velocity and acceleration; the moving mass (and an
// incline's weight) is then fitted with the law.
enum class RawSegmentation { plateaus, trajectory };
std::string_view to_string(RawSegmentation s);
RawSegmentation parse_raw_segmentation(std::string_view name);

// What measured the force. It decides what a diagnosis may name: a constant force signed
// with the motion is a load cell's zero only where a load cell measured it (and the axis's
// mounting is known, or it may be the weight on an incline), a current offset only where a
// motor current did; `unknown` (the default) names neither alone.
enum class ForceSensor { unknown, load_cell, motor_current, torque_sensor };
std::string_view to_string(ForceSensor s);  // "unknown", "load_cell", "motor_current", "torque_sensor"
ForceSensor parse_force_sensor(std::string_view name);

// Two samples of one run at the same time: averaged into one (the default; counted in
// RunSegmentation::averaged_duplicates), or refused.
enum class DuplicateTimes { refuse, average };
std::string_view to_string(DuplicateTimes d);
DuplicateTimes parse_duplicate_times(std::string_view name);

// How a raw log is read: cut into constant-velocity plateaus, or (segmentation) kept whole as
// a trajectory; the drive that turns a motor's quantities into the carriage's; the axis.
struct RawFrictionOptions {
  ForceSign force_sign = ForceSign::follows_motion;
  double max_acceleration_m_s2 = 0.02;  // |a| above it: the block is accelerating (dropped)
  double settling_s = 0.5;              // dropped after every acceleration (load-cell ringing)
  double min_speed_m_s = 1e-4;          // slower: at rest (dropped)
  // A sample whose own (filtered) velocity is off its plateau's median by more than this share
  // is a transient too: at low speed a stop within one sample interval shows as little |a|.
  double velocity_tolerance = 0.02;
  std::size_t min_plateau_samples = 20; // shorter plateaus are dropped
  std::size_t velocity_window = 11;     // samples of the local least-squares slope for v and a (odd, >= 3)
  double moving_mass_kg = 0;            // > 0: the inertia m·a is taken off the force
  DuplicateTimes duplicate_times = DuplicateTimes::average;
  Drive drive;                // a rotary log's joint quantities -> the carriage's (lmcal/io/drive.hpp)
  std::size_t skip_lines = 0; // lines before the column names (a logger's preamble), skipped as read
  RawSegmentation segmentation = RawSegmentation::plateaus;
  // A trajectory's filter window, samples (odd, >= 3); 0: chosen from the data (the smallest
  // whose acceleration noise is under 2 % of the trajectory's RMS acceleration).
  std::size_t trajectory_window = 0;
  // A trajectory's samples within this travel after rest or a reversal: pre-sliding, dropped.
  double presliding_m = 5e-4;
  double axis_incline_deg = 0;  // 0 horizontal, 90 vertical (+x up): a trajectory then fits the weight
  bool incline_stated = false;  // axis_incline_deg was given: the mounting is known (0 included)
  ForceSensor force_sensor = ForceSensor::unknown;
  // InvalidParameter naming the option for a value out of range.
  void validate() const;
};

// One constant-velocity plateau of a raw run.
struct Plateau {
  double start_s = 0, end_s = 0;
  double velocity_m_s = 0;  // signed: the sense of the motion
  std::size_t samples = 0;
};

// What segmentation did with one raw run.
struct RunSegmentation {
  std::string run, file;
  std::size_t samples = 0;               // after duplicate times were averaged
  std::size_t kept = 0;
  std::size_t dropped_acceleration = 0;  // |a| above the threshold
  std::size_t dropped_settling = 0;      // within the settling time after an acceleration
  std::size_t dropped_stationary = 0;    // slower than min_speed
  std::size_t dropped_short = 0;         // in a plateau with too few samples
  std::size_t averaged_duplicates = 0;   // samples merged because they shared a time
  std::vector<Plateau> plateaus;         // kept ones, in time order
  // A trajectory's filter, chosen from the data or given (0 for plateaus): its window, and the
  // noise it leaves in the velocity and the acceleration (from the position's own noise).
  std::size_t filter_window = 0;
  double filter_window_s = 0, velocity_noise_m_s = 0, acceleration_noise_m_s2 = 0;
};

// A raw run as recorded (thinned to at most kMaxPoints), for a plot of what was kept.
struct RawTrace {
  static constexpr std::size_t kMaxPoints = 4000;
  std::string run;
  std::vector<double> time_s, velocity_m_s, force_N;
};

// Where the law's conditions come from. A log need not give them: a drive's log often has
// nothing but speed and force. Without load, preload (in µm: a preload given only as a force,
// preload_N, has none) or block length the paper's scalings cannot be applied; the law is then
// fitted in the combinations one setup determines (fit_friction: the Coulomb level, the
// Stribeck amplitude and speed, the viscous slope, and β where the temperature varies), every
// sample at the neutral conditions below and the setup's stated values kept only to be shown,
// so the log must hold one setup. Without a temperature the law is evaluated at ν40 (T = T_i)
// and β is not fitted. Nothing not logged is invented: outputs print only what was given.
struct FrictionLawConditions {
  static constexpr double kNeutralLoad_N = 1000, kNeutralPreload_um = 1, kNeutralBlockLength_mm = 1;
  static constexpr double kUnloggedTemperature_C = 40;  // T_i: ν = ν40
  bool load = true, preload = true, block_length = true, temperature = true;  // given (column or manifest)
  // The one setup of a combination-law log, as stated (unset: not given).
  std::optional<double> load_N, preload_um, preload_N, block_length_mm;
  std::optional<std::string> preload_class;  // how preload_um was given, when by a catalog class
  // The paper's scalings cannot be applied: the law is fitted in combinations.
  bool combination() const { return !(load && preload && block_length); }
  // The canonical names of the conditions not given ("load_N", "preload_um", ...).
  std::vector<std::string> not_logged() const;
  // "load 1000 N, preload 0.8 N (no µm: the law's preload scaling unknown)": the stated setup.
  std::string stated() const;
};

// Columns, one entry per kept sample (struct of arrays: fast to load and to fit).
struct FrictionLog {
  std::vector<std::string> run_names;    // run index -> name as written in the file(s)
  std::vector<std::string> guide_names;  // guide index -> model ("" when the file has no guide column)
  std::vector<std::uint32_t> run;        // index into run_names
  std::vector<std::uint32_t> guide;      // index into guide_names
  std::vector<double> time_s;            // NaN when the file has no time column
  std::vector<double> velocity_m_s;
  std::vector<double> load_N;
  std::vector<double> preload_um;
  std::vector<double> block_length_mm;
  std::vector<double> temperature_C;
  std::vector<double> friction_N;
  std::vector<double> viscosity40_mm2_s;
  std::vector<std::int8_t> direction;    // +1 or -1
  std::vector<double> acceleration_m_s2; // signed in x; 0 but for a trajectory's samples
  // A raw log's travel (0 in a tidy log): the position (the log's own origin, or the velocity's
  // integral from the run's start), and the travel and time since the carriage last reversed or
  // rested (NaN time without one in the run) — the covariates of position-periodic and
  // pre-sliding friction.
  std::vector<double> position_m;
  std::vector<double> distance_since_reversal_m;
  std::vector<double> time_since_reversal_s;
  std::vector<std::uint32_t> line;       // the sample's row in its file (a raw log's: the row kept); 0: not from a file
  std::vector<LoadReport> reports;       // one per file loaded
  std::vector<RunSegmentation> segmentation;  // one per raw run (none for a tidy log)
  std::vector<RawTrace> raw_traces;           // one per raw run
  // Read as a trajectory (RawSegmentation::trajectory): the force carries the drive's inertia
  // (and on an incline the weight), fitted with the law (friction_fit.hpp, drive_effects).
  bool trajectory = false;
  double axis_incline_deg = 0;  // the axis's mounting: 0 horizontal, 90 vertical with +x up
  FrictionLawConditions law;    // what was given; a combination law's columns hold the neutral values
  ForceSensor force_sensor = ForceSensor::unknown;  // as stated (RawFrictionOptions)
  bool incline_stated = false;                      // the axis's mounting was stated

  std::size_t size() const { return friction_N.size(); }
  // The operating point of sample i for the friction law, direction included (ν_ref is per
  // sample: viscosity40_mm2_s).
  // Inline: the fit's row loops call it per sample and pass (out of line it was a seventh of a
  // 100 k-sample fit's time).
  FrictionConditions<double> conditions(std::size_t i) const {
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
  // Appends one sample to every column.
  void append(std::uint32_t run_index, std::uint32_t guide_index, double time, const FrictionConditions<double>& c,
              double friction, double viscosity40, std::uint32_t source_line = 0);
};

FrictionLog load_friction_log(const std::filesystem::path& file, const RawFrictionOptions& raw = {});
// Several files into one log; run names are shared across files (same name = same run).
FrictionLog load_friction_logs(const std::vector<std::filesystem::path>& files, const RawFrictionOptions& raw = {});

// The conditions of a run that a manifest gives instead of columns (unset: from a column).
struct FrictionRunConditions {
  std::optional<std::string> guide;
  std::optional<double> load_N, preload_um, block_length_mm, temperature_C, viscosity40_mm2_s;
  std::optional<double> preload_N;           // a preload known only as a force (no µm: a combination law)
  std::optional<std::string> preload_class;  // "normal", "C1", "C0": preload_um from the class (preload_class_um)
  bool block_length_from_catalog = false;  // the guide's catalog value: a column may still give it
  std::string block_length_note;           // why the guide's catalog could not give it ("" = it did, or no guide)
};

// A friction manifest (TOML): the files of a data set and their runs' fixed conditions.
//   name = "rig A"
//   catalog = "guides.toml"          # optional: a user catalog for the guides named
//   file = "friction.csv"            # optional: one file holding every run (a run column)
//   [raw]                            # optional: how raw logs are segmented (the flags' names)
//   force_sign = "opposes-motion"
//   moving_mass_kg = 2.4
//   [[run]]
//   id = "r1"
//   file = "friction/r1.csv"         # the run's own file (no run column needed), or omit
//   guide = "SRN 35C"                # block_length_mm defaults to the catalog's
//   load_N = 1000                    # any unit of the quantity: load_kgf, temperature_K, ...
//   preload_um = 2.5
//   temperature_C = 24
//   viscosity40_mm2_s = 99
//   # preload_class = "C0"           # instead of preload_um (preload_class_um)
//   # preload_N = 0.8                # a spring's preload force: no µm, a combination law
// Keys and columns must not both give a quantity; a run the files hold but the manifest does
// not list needs its conditions as columns.
struct FrictionDataSet {
  std::string name;
  std::filesystem::path manifest;
  std::string catalog_file;             // the user catalog used ("" = built-in only)
  RawFrictionOptions raw;               // as the manifest's [raw] table sets them
  std::vector<std::filesystem::path> files;
  FrictionLog log;
};
// `user_catalog` (a --catalog given on the command line) wins over the manifest's `catalog`;
// `raw` set by the caller (flags) wins over the manifest's [raw] table key by key when
// `raw_given` names them ("force_sign", "moving_mass_kg", ...). The files it names must lie
// inside `scope` (input_scope.hpp: by default the manifest's folder).
FrictionDataSet load_friction_dataset(const std::filesystem::path& manifest, const GuideCatalog* user_catalog = nullptr,
                                      const RawFrictionOptions& raw = {},
                                      const std::vector<std::string>& raw_given = {}, const InputScope& scope = {});

// The preload (µm) of a THK preload class for SRG/SRN guides, the middle of the class's radial
// clearance (PHYSICS.md §1a): normal 1.5, C1 2.5, C0 4 (3.5 for size 25, e.g. "SRG 25C"; the
// paper's pc = 2.5 and 4). InvalidParameter naming the classes otherwise.
double preload_class_um(std::string_view preload_class, std::string_view guide = {});

// Writes a log in the canonical units (the inverse of load_friction_log), with the given
// '#' comment lines first.
std::string friction_log_csv(const FrictionLog& log, const std::vector<std::string>& comments = {});

}  // namespace lmcal
