// The reading of one friction-log file (private to io's friction-log loader, friction_log.cc):
// the log's columns, the names of runs and guides, a raw run's samples, and FileLoader, which
// binds a file's header and reads its rows (friction_file_loader.cc), in slices read side by
// side where it is large and tidy (friction_file_slices.cc), a raw file's runs cut into
// plateaus (friction_raw_runs.cc).
#pragma once

#include <fmt/format.h>

#include <array>
#include <cstdint>
#include <filesystem>
#include <limits>
#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <tuple>
#include <vector>

#include "io/csv_reader.hpp"
#include "io/friction_files.hpp"
#include "io/raw_friction.hpp"
#include "lmcal/io/friction_log.hpp"
#include "lmcal/io/limits.hpp"

namespace lmcal::detail::friction_reading {

using csv::Rule;

constexpr double kDefaultViscosity40_mm2_s = 99.0;  // ν_i of Eq. 6 (PHYSICS.md §2)

// A log's per-sample columns, as members: those a row fills with its values, and the indices
// (run, guide, source line) that change when slices of a file are joined.
inline constexpr auto kValueColumns =
    std::make_tuple(&FrictionLog::time_s, &FrictionLog::velocity_m_s, &FrictionLog::load_N, &FrictionLog::preload_um,
                    &FrictionLog::block_length_mm, &FrictionLog::temperature_C, &FrictionLog::friction_N,
                    &FrictionLog::viscosity40_mm2_s, &FrictionLog::direction, &FrictionLog::acceleration_m_s2,
                    &FrictionLog::position_m, &FrictionLog::distance_since_reversal_m, &FrictionLog::time_since_reversal_s);
inline constexpr auto kIndexColumns = std::make_tuple(&FrictionLog::run, &FrictionLog::guide, &FrictionLog::line);

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

inline std::string header_of(Spec spec) {
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
std::string_view name_cell(const csv::Reader& reader, const csv::Column& column, std::string& scratch);

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
             NameIndex& guides);

  // Reads the rows: line by line when `sliced` is null; else a large tidy file in slices, one
  // per thread, setting *sliced first (what then throws is read again line by line by the
  // caller: see read_slices).
  void load(bool* sliced);

  // Room for `capacity` rows in every column of `log`.
  static void reserve(FrictionLog& log, std::size_t capacity);

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

  void read_rows();

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
  void read_slices(int count);

  // A later slice's rows as this file's log will hold them: its run and guide indices mapped to
  // the log's, its line numbers after `lines_before`.
  struct JoinedPart {
    const FrictionLog* log;
    std::vector<std::uint32_t> run_map, guide_map;
    long lines_before;
  };

  // The names, the combination law's setup and each run's last sample (`last`, by the log's run
  // index) of `part`, a later slice, joined to this file's (see read_slices); its rows are
  // appended afterwards with the other slices' (append_parts).
  JoinedPart join(const FileLoader& part, long lines_before, std::vector<LastSample>& last);

  // The rows of `parts`, in order, appended to the log: each column on a free thread.
  void append_parts(const std::vector<JoinedPart>& parts);

  // A combination law's setup as a later slice stated it (see law_conditions): the log's first
  // values, or SlicesDisagree.
  void join_law(const FrictionLawConditions& from);

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
  void bind_drive();

  // Which columns the file has decides its kind (tidy or raw) and what the manifest must give.
  void bind();

  // Which of the law's conditions this file gives (a column, or a key of some run of the
  // manifest: then every run needs it); the log's files must agree.
  void bind_law();
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
  const FrictionRunConditions* manifest_conditions(std::uint32_t run_index);

  // Without a guide column, a run's guide is the manifest's (or none): looked up once per run.
  std::uint32_t run_guide(std::uint32_t run_index, const FrictionRunConditions* given);

  // A condition of the current row: its column, else the manifest's value, else `fallback`.
  double condition(Spec spec, std::optional<double> FrictionRunConditions::*field, const FrictionRunConditions* c,
                   double fallback = 0) const {
    if (const csv::Column* col = column(spec)) return reader_.number(*col, false);
    return c && (c->*field) ? *(c->*field) : fallback;
  }

  // The index of a run or guide name; a name seen for the first time is checked (UTF-8,
  // printable) and counted against the limit.
  std::uint32_t name_index(NameIndex& names, const csv::Column& column, std::string_view name, std::string_view what);

  // The run of a file without a run column: the manifest's, or one named after the file.
  const std::string& file_run_name() {
    if (!file_run_name_) file_run_name_ = file_.run.empty() ? default_run_name() : file_.run;
    return *file_run_name_;
  }

  // A file without a run column or a manifest's run: one run, named after the file.
  std::string default_run_name();

  bool logged(Spec spec) const;

  // A row's conditions as the law sees them: a combination law's at the neutral values (each
  // stated one checked to be the log's one setup), an unlogged temperature at T_i.
  FrictionConditions<double> law_conditions(FrictionConditions<double> c, const FrictionRunConditions* given);

  void read_row(std::string& scratch);

  // Time must not decrease within a run (within this file); a raw log's repeated time is
  // refused or merged (returns true: merge into the previous sample).
  bool check_time_order(std::uint32_t run_index, double t, bool raw);

  void read_raw_row(std::uint32_t run_index, std::uint32_t guide_index, double t, const FrictionConditions<double>& c,
                    double nu40);

  // Each raw run cut into plateaus; the kept samples go into the log.
  void segment_raw_runs();

  static RawTrace thin_trace(const std::string& run, const raw::RunSamples& samples, const raw::Segmented& s);

  // A tidy log's friction is a magnitude; negative values where the block moves backwards
  // are a signed force given in the wrong column.
  void warn_signed_friction();


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

}  // namespace lmcal::detail::friction_reading
