#include "lmcal/fleet/fleet.hpp"

#include <fmt/format.h>
#include <nlohmann/json.hpp>
#include <omp.h>

#include <algorithm>
#include <atomic>
#include <exception>
#include <map>
#include <mutex>
#include <set>
#include <thread>

#include "io/input_file.hpp"
#include "io/manifest.hpp"
#include "lmcal/error.hpp"
#include "lmcal/fleet/fleet_record.hpp"
#include "lmcal/io/atomic_file.hpp"
#include "lmcal/io/date.hpp"
#include "lmcal/io/hash.hpp"
#include "lmcal/report/calibration.hpp"

namespace lmcal {

namespace fs = std::filesystem;

std::string FleetSet::series() const { return fleet_series(unit, axis); }

namespace {

// --- finding the sets ---------------------------------------------------------------------------

bool holds_measurements(const fs::path& dir) {
  std::error_code ec;
  for (auto it = fs::directory_iterator(dir, ec); !ec && it != fs::directory_iterator(); it.increment(ec))
    if (it->is_regular_file(ec) && is_measurement_file(it->path())) return true;
  return false;
}

// `path` relative to `base`, '/'-separated ("." for base itself); both made absolute first.
std::string relative_id(const fs::path& path, const fs::path& base) {
  auto normal = [](const fs::path& p) {
    fs::path n = fs::absolute(p).lexically_normal();
    return n.has_filename() ? n : n.parent_path();  // "a/" is "a"
  };
  return normal(path).lexically_relative(normal(base)).generic_string();
}

bool escapes(const std::string& relative) { return relative.empty() || *fs::path(relative).begin() == ".."; }

bool is_inside(const fs::path& path, const fs::path& folder) {
  if (folder.empty()) return false;
  return !escapes(relative_id(path, folder));
}

// The id of the set in `dir`: the folder relative to the root. A folder outside the root (read
// only with --allow-outside-root) is named "outside/<its absolute path>", so that its outputs,
// OUT/<id>, still go under OUT. `problem` gets the reason when the id cannot name outputs (not
// UTF-8, a control character).
std::string set_id(const fs::path& dir, const fs::path& root, std::optional<std::string>& problem) {
  std::string id = relative_id(dir, root);
  if (escapes(id)) id = "outside" + fs::absolute(dir).lexically_normal().generic_string();
  if (auto p = io::name_problem(id)) problem = fmt::format("folder name {}: {}", io::printable(id), *p);
  return id;
}

// A folder name that is a date: "YYYY-MM-DD" and a real day.
bool is_date(std::string_view text) { return io::parse_iso_date(text).has_value(); }

// Unit and date from the folder: ".../unit/YYYY-MM-DD" or ".../unit".
void infer_unit_and_date(FleetSet& s, const fs::path& root) {
  const fs::path id(s.id);
  const std::string last = id.filename().string();
  if (is_date(last)) {
    s.date = last;
    const std::string above = id.parent_path().generic_string();
    s.unit = above.empty() ? fs::absolute(root).lexically_normal().parent_path().filename().string() : above;
  } else {
    s.unit = s.id == "." ? fs::absolute(root).lexically_normal().filename().string() : s.id;
  }
}

std::vector<FleetSet> walk_folders(const fs::path& root, const fs::path& exclude, bool allow_outside) {
  std::vector<FleetSet> sets;
  auto consider = [&](const fs::path& dir) {
    if (!holds_measurements(dir)) return;
    std::optional<std::string> problem;
    FleetSet s{.id = set_id(dir, root, problem), .dir = dir};
    if (problem) throw InputError(io::printable(dir.string()), 0, 0, *problem);
    infer_unit_and_date(s, root);
    sets.push_back(std::move(s));
  };
  consider(root);
  std::error_code ec;
  // Links to folders are not followed down (a loop cannot trap the walk), and one that leads
  // outside ROOT is refused before anything in it is read.
  for (auto it = fs::recursive_directory_iterator(root, fs::directory_options::skip_permission_denied, ec);
       it != fs::recursive_directory_iterator(); it.increment(ec)) {
    if (ec) throw InputError(io::printable(root.string()), 0, 0, "cannot list folder: " + ec.message());
    std::error_code kind;
    if (!it->is_directory(kind)) continue;  // a file, or a link that leads nowhere (a loop, a missing target)
    if (it->path().filename().string().starts_with(".") || is_inside(it->path(), exclude)) {
      it.disable_recursion_pending();
      continue;
    }
    if (it->is_symlink(kind))
      if (auto problem = outside_scope(it->path(), root, {.root = root, .allow_outside = allow_outside}))
        throw InputError(io::printable(it->path().string()), 0, 0, fmt::format("this folder {}", *problem));
    consider(it->path());
  }
  return sets;
}

// fleet.toml: the sets, each with its unit, axis, machine and date.
std::vector<FleetSet> read_fleet_file(const fs::path& root, const fs::path& file, bool allow_outside) {
  const manifest::Manifest m{.file = file.string(), .folder = root};
  const toml::table top = m.parse();
  for (const auto& [key, node] : top)
    if (key.str() != "set") m.fail(key.source(), fmt::format("unknown key '{}': expected [[set]] tables", key.str()));
  const toml::node* list_node = top.get("set");
  const toml::array* list = list_node ? list_node->as_array() : nullptr;
  if (!list) throw InputError(file.string(), 1, 1, "expected [[set]] tables (folder, unit, axis, machine, date)");
  std::vector<FleetSet> sets;
  for (const toml::node& item : *list) {
    const toml::table& t = manifest::table_of(m, item, "[[set]]");
    FleetSet s;
    const toml::node* folder = nullptr;
    for (const auto& [key, node] : t) {
      const std::string k(key.str());
      if (k == "folder") {
        folder = &node;
        const std::string& name = manifest::string_of(m, key, node);
        s.dir = root / name;
        // Before the folder is looked at: whether it exists outside ROOT is not ours to tell.
        if (auto problem = outside_scope(s.dir, root, {.root = root, .allow_outside = allow_outside}))
          m.fail(node.source(), fmt::format("folder '{}' {}", name, *problem));
      } else if (k == "unit" || k == "axis" || k == "machine") {
        std::string& field = k == "unit" ? s.unit : k == "axis" ? s.axis : s.machine;
        field = manifest::string_of(m, key, node);
        if (field.empty()) m.fail(node.source(), fmt::format("expected a non-empty {}", k));
      } else if (k == "date") {
        if (const auto* d = node.as_date())
          s.date = fmt::format("{:04}-{:02}-{:02}", d->get().year, d->get().month, d->get().day);
        else if (node.is_string() && is_date(manifest::string_of(m, key, node)))
          s.date = manifest::string_of(m, key, node);
        else
          m.fail(node.source(), "expected a date: 2026-09-01 or \"2026-09-01\"");
      } else {
        m.fail(key.source(), fmt::format("unknown key '{}': expected folder, unit, axis, machine, date", k));
      }
    }
    if (!folder) m.fail(t.source(), "expected folder = \"...\" (the set's folder, relative to the fleet's root)");
    std::error_code ec;
    if (!fs::is_directory(s.dir, ec))
      m.fail(folder->source(), fmt::format("folder {} does not exist{}", io::printable(s.dir.string()), ec ? " (" + ec.message() + ")" : ""));
    if (fs::directory_iterator(s.dir, ec); ec)
      m.fail(folder->source(), fmt::format("folder {} cannot be read: {}", io::printable(s.dir.string()), ec.message()));
    if (!holds_measurements(s.dir))
      m.fail(folder->source(), fmt::format("folder {} holds no measurements (friction*.csv, friction*.toml, thermal*.toml)",
                                           io::printable(s.dir.string())));
    std::optional<std::string> problem;
    s.id = set_id(s.dir, root, problem);
    if (problem) m.fail(folder->source(), *problem);
    if (s.unit.empty()) {
      const std::string date = s.date;
      infer_unit_and_date(s, root);
      if (!date.empty()) s.date = date;
    }
    for (const FleetSet& other : sets) {
      if (other.id == s.id) m.fail(folder->source(), fmt::format("folder {} is listed twice", s.id));
      if (other.unit == s.unit && other.axis == s.axis && other.date == s.date)
        m.fail(t.source(), fmt::format("unit {} has two sets dated '{}' ({} and {})", s.series(), s.date, other.id, s.id));
    }
    sets.push_back(std::move(s));
  }
  return sets;
}

// --- a set's inputs -----------------------------------------------------------------------------

bool is_lmcal_output(const std::string& name) {
  return is_calibration_output(name) || name == kFleetRecordFile || name.ends_with(".tmp");
}

InputScope scope_of(const Fleet& fleet) { return {.root = fleet.root, .allow_outside = fleet.allow_outside_root}; }

// Every file of the set's folder (and below) that may be an input: all but lmcal's outputs,
// hidden files, the output folder and links out of the root (never read, not even hashed).
// Relative to the root, sorted.
std::vector<std::string> folder_files(const Fleet& fleet, const FleetSet& s, const fs::path& output_dir) {
  std::vector<std::string> files;
  std::error_code ec;
  for (auto it = fs::recursive_directory_iterator(s.dir, fs::directory_options::skip_permission_denied, ec);
       it != fs::recursive_directory_iterator(); it.increment(ec)) {
    if (ec) throw InputError(s.dir.string(), 0, 0, "cannot list folder: " + ec.message());
    const std::string name = it->path().filename().string();
    if (name.starts_with(".") || (it->is_directory() && is_inside(it->path(), output_dir))) {
      if (it->is_directory()) it.disable_recursion_pending();
      continue;
    }
    std::error_code kind;
    if (it->is_regular_file(kind) && !is_lmcal_output(name) && !outside_scope(it->path(), fleet.root, scope_of(fleet)))
      files.push_back(relative_id(it->path(), fleet.root));
  }
  std::sort(files.begin(), files.end());
  return files;
}

// OUT/<id>: under OUT whatever the id (discovery derives ids that cannot climb out; this
// guards the invariant for fleets built by hand).
fs::path set_output_folder(const fs::path& output_dir, const FleetSet& s) {
  if (escapes(s.id) || fs::path(s.id).is_absolute())
    throw InvalidParameter("set id", fmt::format("'{}' would write outside the output folder", io::printable(s.id)));
  return output_dir / s.id;
}

// The files an earlier run of set `id` wrote in `out`, as its record lists them: what this run
// may remove. None when there is no record of this set there (the folder is someone else's).
// A record of an lmcal that did not list them: the names a calibration writes.
std::vector<std::string> earlier_outputs(const fs::path& out, const std::string& id) {
  try {
    const fs::path file = out / kFleetRecordFile;
    std::error_code ec;
    if (!fs::is_regular_file(file, ec)) return {};
    const FleetRecord earlier = parse_fleet_record(io::read_text_file(file, "fleet record"), file.string());
    if (earlier.id != id) return {};
    std::vector<std::string> names = earlier.outputs.value_or(calibration_output_names());
    std::erase_if(names, [](const std::string& name) { return !is_calibration_output(name); });  // a plain name of ours only
    return names;
  } catch (const std::exception&) {
    return {};  // unreadable: nothing of it is trusted
  }
}

// The OpenMP team size of this thread's parallel regions, for a scope (the caller's setting back after).
class ThreadTeam {
 public:
  explicit ThreadTeam(int threads) : before_(omp_get_max_threads()) { omp_set_num_threads(threads); }
  ~ThreadTeam() { omp_set_num_threads(before_); }
  ThreadTeam(const ThreadTeam&) = delete;
  ThreadTeam& operator=(const ThreadTeam&) = delete;

 private:
  int before_;
};

}  // namespace

Fleet discover_fleet(const fs::path& root, const fs::path& exclude, bool allow_outside_root) {
  std::error_code ec;
  if (!fs::is_directory(root, ec))
    throw InputError(io::printable(root.string()), 0, 0, "expected the fleet's folder (a folder of measurement folders)");
  io::check_path_name(fs::absolute(root), "folder name");
  Fleet fleet{.root = root, .allow_outside_root = allow_outside_root};
  const fs::path file = root / "fleet.toml";
  if (fs::symlink_status(file, ec).type() != fs::file_type::not_found) {  // a link to itself is read, and refused
    fleet.sets = read_fleet_file(root, file, allow_outside_root);
    fleet.source = "fleet.toml";
  } else {
    fleet.sets = walk_folders(root, exclude, allow_outside_root);
    fleet.source = "folders";
  }
  if (fleet.sets.empty())
    throw InputError(root.string(), 0, 0,
                     "no measurement folders: expected folders holding friction*.csv, friction*.toml or thermal*.toml "
                     "(one per unit, or per unit and date), or a fleet.toml listing them");
  std::sort(fleet.sets.begin(), fleet.sets.end(), [](const FleetSet& a, const FleetSet& b) { return a.id < b.id; });
  return fleet;
}

std::string fleet_options_hash(const CalibrationOptions& options) {
  return sha256_text(std::string("lmcal ") + LMCAL_VERSION + "\n" + calibration_options_json(options));
}

std::optional<std::string> up_to_date_record(const Fleet& fleet, std::size_t index, const FleetOptions& options,
                                             const std::string& options_hash) {
  const FleetSet& s = fleet.sets.at(index);
  const fs::path out = set_output_folder(options.output_dir, s);
  const fs::path file = out / kFleetRecordFile;
  if (!fs::is_regular_file(file)) return std::nullopt;
  std::string text;
  try {
    text = io::read_text_file(file, "fleet record");
    const FleetRecord r = parse_fleet_record(text);
    if (r.id != s.id || r.options_sha256 != options_hash || r.lmcal_version != LMCAL_VERSION) return std::nullopt;
    if (r.status == "ok" && !fs::is_regular_file(out / "calibration.json")) return std::nullopt;
    std::map<std::string, std::string> recorded(r.inputs.begin(), r.inputs.end());
    for (const std::string& f : folder_files(fleet, s, options.output_dir))
      if (!recorded.contains(f)) return std::nullopt;  // a file added since
    for (const auto& [f, hash] : recorded) {
      const fs::path p = fleet.root / f;
      if (outside_scope(p, fleet.root, scope_of(fleet))) return std::nullopt;  // not read to compare
      if (!fs::is_regular_file(p) || sha256_file(p) != hash) return std::nullopt;
    }
  } catch (const std::exception&) {
    return std::nullopt;  // unreadable or of another shape: made again
  }
  return text;
}

FleetSetOutcome run_fleet_set(const Fleet& fleet, std::size_t index, const FleetOptions& options,
                              const std::string& options_hash) {
  if (auto record = up_to_date_record(fleet, index, options, options_hash))
    return {.record = *record, .computed = false, .failed = parse_fleet_record(*record).status != "ok"};
  const FleetSet& s = fleet.sets.at(index);
  const fs::path out = set_output_folder(options.output_dir, s);
  FleetRecord r{.id = s.id, .unit = s.unit, .axis = s.axis, .machine = s.machine, .date = s.date,
                .lmcal_version = LMCAL_VERSION, .options_sha256 = options_hash};
  OutputSet files;
  std::set<std::string> inputs;
  r.outputs.emplace();
  try {
    for (const std::string& f : folder_files(fleet, s, options.output_dir)) inputs.insert(f);
    CalibrationOptions calibration = options.calibration;
    calibration.inputs = scope_of(fleet);
    calibration.inputs.allow_outside |= options.calibration.inputs.allow_outside;
    const Calibration c = calibrate(find_calibration_set(s.dir), calibration);
    for (const auto& [file, hash] : c.inputs) inputs.insert(relative_id(file, fleet.root));
    for (const auto& [name, text] : calibration_outputs(c)) {
      files.add(out / name, text);
      r.outputs->push_back(name);
    }
    fill_fleet_record(r, c);
  } catch (const std::exception& e) {
    r.status = "failed";
    r.error = dynamic_cast<const std::bad_alloc*>(&e) ? "out of memory while calibrating this set (docs/formats.md#limits)"
                                                      : e.what();
    files = OutputSet();
    r.outputs->clear();
  }
  // Outputs of an earlier calibration of this set that this one did not write (a failed set
  // writes none) would now mislead: removed in the same commit. Only those its record lists.
  for (const std::string& name : earlier_outputs(out, s.id)) files.remove(out / name);
  for (const std::string& f : inputs) {
    std::error_code ec;
    r.inputs.emplace_back(f, fs::is_regular_file(fleet.root / f, ec) ? sha256_file(fleet.root / f) : "missing");
  }
  std::string record = fleet_record_json(r);
  files.add(out / kFleetRecordFile, record);  // last: a record on disk means the outputs are whole
  files.commit();
  return {.record = std::move(record), .computed = true, .failed = r.status != "ok"};
}

FleetRun run_fleet(const Fleet& fleet, const FleetOptions& options, const FleetProgress& progress) {
  if (options.shards == 0 || options.shard >= options.shards)
    throw InvalidParameter("--shard", fmt::format("shard {} of {}: expected i/n with 0 <= i < n", options.shard, options.shards));
  const std::string hash = fleet_options_hash(options.calibration);
  FleetRun run;
  run.records.resize(fleet.sets.size());
  std::vector<std::size_t> mine;
  for (std::size_t i = 0; i < fleet.sets.size(); ++i)
    if (i % options.shards == options.shard) mine.push_back(i);
  std::atomic<std::size_t> next{0};
  std::mutex mutex;
  std::size_t done = 0;
  std::exception_ptr error;
  auto work = [&] {
    std::optional<ThreadTeam> one;  // the jobs already fill the cores: a set's OpenMP loops on one thread
    if (options.jobs > 1) one.emplace(1);
    for (std::size_t k; (k = next++) < mine.size();) {
      {
        const std::lock_guard lock(mutex);
        if (error) return;
      }
      try {
        FleetSetOutcome outcome = run_fleet_set(fleet, mine[k], options, hash);
        const std::lock_guard lock(mutex);
        (outcome.computed ? run.computed : run.skipped) += 1;
        run.failed += outcome.failed ? 1 : 0;
        ++done;
        if (progress) progress(done, mine.size(), fleet.sets[mine[k]].id, outcome);
        run.records[mine[k]] = std::move(outcome.record);
      } catch (...) {  // the outputs could not be written: the fleet stops
        const std::lock_guard lock(mutex);
        if (!error) error = std::current_exception();
      }
    }
  };
  std::vector<std::thread> threads;
  for (std::size_t j = 1; j < std::max<std::size_t>(1, options.jobs); ++j) threads.emplace_back(work);
  work();
  for (auto& t : threads) t.join();
  if (error) std::rethrow_exception(error);
  return run;
}

std::vector<std::string> read_fleet_records(const Fleet& fleet, const FleetOptions& options) {
  const std::string hash = fleet_options_hash(options.calibration);
  std::vector<std::string> records, missing;
  for (std::size_t i = 0; i < fleet.sets.size(); ++i) {
    if (auto r = up_to_date_record(fleet, i, options, hash))
      records.push_back(std::move(*r));
    else
      missing.push_back(fleet.sets[i].id);
  }
  if (!missing.empty()) {
    const std::size_t shown = std::min<std::size_t>(missing.size(), 5);
    throw InputError(options.output_dir.string(), 0, 0,
                     fmt::format("{} of {} sets have no up-to-date results ({}{}): run the shards that did not finish, "
                                 "or `lmcal fleet {}` with the same options (it calibrates only those)",
                                 missing.size(), fleet.sets.size(),
                                 fmt::join(missing.begin(), missing.begin() + static_cast<std::ptrdiff_t>(shown), ", "),
                                 missing.size() > shown ? ", …" : "", fleet.root.string()));
  }
  return records;
}

}  // namespace lmcal
