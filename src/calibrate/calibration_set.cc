// Finding a measurement set: what a folder holds, and which files are lmcal's own outputs.
#include "lmcal/calibrate/calibration.hpp"

#include <fmt/format.h>

#include <algorithm>

#include "io/input_file.hpp"
#include "lmcal/error.hpp"

namespace lmcal {

namespace fs = std::filesystem;

const std::vector<std::string>& calibration_output_names() {
  static const std::vector<std::string> names = {
      "model.toml",         "calibrated_friction.json", "calibrated_thermal.json", "friction.json",
      "friction_samples.csv", "friction_conditions.csv", "friction_diagnosis.json", "thermal.json",
      "thermal_samples.csv",  "thermal_alpha_curve.csv", "thermal_diagnosis.json", "prediction.json",
      "prediction_time.csv",  "plan_friction.json",      "plan_friction_template.csv", "plan_thermal.json",
      "plan_thermal_manifest.toml", "calibration.json",  "report.html"};
  return names;
}

bool is_calibration_output(std::string_view file_name) {
  const auto& names = calibration_output_names();
  return std::find(names.begin(), names.end(), file_name) != names.end();
}

namespace {

bool is_friction_log_name(const fs::path& file) {
  return file.filename().string().starts_with("friction") && file.extension() == ".csv";
}

bool is_manifest_name(const fs::path& file, std::string_view kind) {
  return file.filename().string().starts_with(kind) && file.extension() == ".toml";
}

}  // namespace

bool is_measurement_file(const fs::path& file) {
  return (is_friction_log_name(file) && !is_calibration_output(file.filename().string())) ||
         is_manifest_name(file, "friction") || is_manifest_name(file, "thermal");
}

CalibrationSet find_calibration_set(const fs::path& dir) {
  if (!fs::is_directory(dir)) throw InputError(dir.string(), 0, 0, "expected a measurement folder (friction*.csv, thermal*.toml)");
  CalibrationSet set;
  set.dir = dir;
  set.name = fs::weakly_canonical(dir).filename().string();
  io::check_path_name(fs::weakly_canonical(dir), "folder name");
  std::vector<fs::path> manifests, friction_manifests;
  for (const auto& entry : fs::directory_iterator(dir)) {
    if (!entry.is_regular_file()) continue;
    const std::string file = entry.path().filename().string();
    if (is_friction_log_name(entry.path())) {
      // `calibrate -o SET` writes friction_samples.csv beside the logs: never read it back.
      if (is_calibration_output(file)) {
        set.ignored_files.push_back(entry.path());
        continue;
      }
      set.friction_logs.push_back(entry.path());
    }
    if (is_manifest_name(entry.path(), "thermal")) manifests.push_back(entry.path());
    if (is_manifest_name(entry.path(), "friction")) friction_manifests.push_back(entry.path());
  }
  std::sort(set.friction_logs.begin(), set.friction_logs.end());
  std::sort(manifests.begin(), manifests.end());
  if (manifests.size() > 1)
    throw InputError(manifests[1].string(), 0, 0,
                     fmt::format("expected one thermal manifest in {}, found {} (thermal*.toml)", dir.string(), manifests.size()));
  if (!manifests.empty()) set.thermal_manifest = manifests.front();
  std::sort(friction_manifests.begin(), friction_manifests.end());
  if (friction_manifests.size() > 1)
    throw InputError(friction_manifests[1].string(), 0, 0,
                     fmt::format("expected one friction manifest in {}, found {} (friction*.toml)", dir.string(),
                                 friction_manifests.size()));
  if (!friction_manifests.empty()) set.friction_manifest = friction_manifests.front();
  if (set.friction_logs.empty() && !set.friction_manifest && !set.thermal_manifest)
    throw InputError(dir.string(), 0, 0,
                     "expected friction logs (friction*.csv or a friction*.toml manifest) or a thermal manifest "
                     "(thermal*.toml) in the folder");
  return set;
}

}  // namespace lmcal
