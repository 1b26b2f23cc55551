// Use the calibrated model: the rail's temperature, its thermal elongation and the positioning
// error of a linear scale fixed to it over a duty cycle, every quantity with a band from the
// model's parameter covariance (`lmcal predict MODEL DUTY`).
//
// The duty cycle (TOML):
//   guide = "SRN 35C"            # catalog guide: rail section, material, block and contact lengths
//   rail_length_m = 0.6
//   ambient_C = 24               # or ambient_trace = [[t_s, T_C], ...] from the duty's start
//   initial_C = 24               # optional: the rail's uniform start (default: the ambient at 0)
//   positions_m = [0, 0.1]       # where the temperature is reported, from the rail centre
//   output_every_s = 60
//   repeat = 4                   # optional: the segments run this many times
//   [scale]                      # optional: a linear scale fixed to the rail
//   from_m = -0.25, to_m = 0.25  # its span along the rail (default: the whole rail)
//   mounting = "end"             # fixed at from_m ("end") or at the span's centre ("centre")
//   expansion_per_K = 11.5e-6    # default: steel
//   positions_m = [0.25]         # where its error is reported (default: the span's ends)
//   [[segment]]
//   duration_s = 3600
//   velocity_m_s = 0.11          # 0: idle (no heat)
//   load_N = 3000, stroke_m = 0.2
//   preload_um, block_length_mm, viscosity40_mm2_s   # optional: the guide's / 99 by default
//
// Each segment is simulated from the rail's state at the end of the one before (mechanisms
// included: a coupled heat follows the rail, a forced convection the speed). The band: the
// model's parameters drawn from their covariance (multivariate normal), the duty simulated for
// each draw, the 2.5 and 97.5 percentiles at every output. Where the heat comes from the
// friction law, the friction constants are drawn from theirs and α with them so that the heat
// the calibration runs put into the rail, α·Q, stays what was fitted (α's covariance given the
// heat, the calibration's heat references); α's run-to-run spread is added where the
// calibration found one. A duty outside the calibrated speeds, loads or temperatures is flagged.
//
// Thermal elongation: the scale's graduation at x moves by δ(x) = ∫_{x_ref}^{x} α_th ΔT dx'
// (x_ref the fixed point, ΔT from the rail's temperature at the duty's start): a table
// positioned by the scale to x stands at x + δ(x), so δ is its positioning error, positive
// away from the fixed point. The rail's own elongation is ∫ α_th ΔT over its length.
#pragma once

#include "lmcal/export.hpp"

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "lmcal/fit/model_file.hpp"
#include "lmcal/io/catalog.hpp"
#include "lmcal/io/thermal_run.hpp"
#include "lmcal/models/rail_thermal.hpp"

namespace LMCAL_API lmcal {

struct DutySegment {
  std::string name;  // "segment k" (1-based, repeats counted on)
  double duration_s = 0;
  double velocity_m_s = 0;  // 0: idle
  double load_N = 0;
  double stroke_m = 0;
  double preload_um = 0, block_length_mm = 0, viscosity40_mm2_s = 99;
  long line = 0, column = 0;  // its [[segment]] table in the duty file (0: not from a file)
};

enum class ScaleMounting { end, centre };

struct LinearScale {
  double from_m = 0, to_m = 0;  // along the rail, from its centre
  ScaleMounting mounting = ScaleMounting::end;
  double expansion_per_K = 11.5e-6;
  std::vector<double> positions_m;  // where δ is reported
  double fixed_point_m() const { return mounting == ScaleMounting::end ? from_m : 0.5 * (from_m + to_m); }
};

struct DutyCycle {
  std::string file;
  GuideSpec guide;
  double rail_length_m = 0;
  AmbientTrace ambient;               // t from the duty's start
  std::optional<double> initial_C;    // unset: the ambient at 0
  std::vector<double> positions_m;    // temperature outputs
  double output_every_s = 60;
  LinearScale scale;
  std::vector<DutySegment> segments;  // repeats laid out
  double duration_s() const;
};

// The calibration runs' own cycle, the duty the report predicts: the first run's rail, guide,
// load, preload and stroke at the fastest run's speed for the longest run's duration, then as
// long at rest; the ambient constant at `ambient_C`, the temperature at the runs' sensors, a
// scale along the whole rail fixed at its end, outputs every minute.
DutyCycle duty_of_runs(const ThermalDataSet& data, double ambient_C);

// Reads a duty cycle; InputError naming the file, line, column and the field for a missing,
// unknown or non-physical value (a negative duration, a speed or load out of range, a scale off
// the rail, …). Its `catalog` must lie inside `scope` (input_scope.hpp: by default the duty's folder).
DutyCycle load_duty_cycle(const std::filesystem::path& file, const GuideCatalog* user_catalog = nullptr,
                          const InputScope& scope = {});

struct PredictionOptions {
  std::size_t samples = 200;  // parameter draws for the band
  double confidence = 0.95;
  std::uint64_t seed = 1;
  int half_rail_segments = 100;
  double time_step_s = 30;
  // A duty on another guide than the model was calibrated on (ModelFile::guide) is refused: α,
  // h and the friction constants are that guide's rail and block. True: predicted anyway, noted.
  bool any_guide = false;
};

// What predicting `duty` with `options` costs, estimated before anything is allocated: CPU
// seconds on one core and bytes held at once.
struct PredictionCost {
  double cpu_s = 0, bytes = 0;
};
PredictionCost prediction_cost(const DutyCycle& duty, const PredictionOptions& options);

// InvalidParameter when the draws, the rail's segments or the estimate exceed the limits of
// docs/formats.md#limits (kMaxPredictionSamples, kMaxRailSegments, kMaxPredictionBytes,
// kMaxPredictionCpu_s): "duty: d.toml: 100000 segments, … would take some 9.1 CPU hours …".
void check_prediction_size(const DutyCycle& duty, const PredictionOptions& options);

// A predicted quantity over time: the model's value at its estimates and the band.
struct Band {
  std::vector<double> value, low, high;
};

struct RangeFlag {
  std::string segment, quantity;  // "velocity_m_s", "load_N", "temperature_C"
  double value = 0, low = 0, high = 0;  // the duty's value and the calibrated range
  std::string what;                     // "friction" or "thermal" calibration
};

struct Prediction {
  std::vector<double> time_s;
  std::vector<std::string> segment;     // at each output time
  std::vector<double> positions_m;
  std::vector<Band> temperature_C;      // one per position
  Band elongation_um;                   // the whole rail
  std::vector<double> scale_positions_m;
  std::vector<Band> scale_error_um;     // δ at each scale position
  Band friction_N, heat_rate_W;         // of the block (0 while idle)
  std::vector<double> profile_x_m;      // along the rail at the end of the duty
  Band profile_C;
  std::size_t samples = 0;              // draws that ran
  std::string method;                   // how the band was made, in words
  std::vector<std::string> notes;       // what the band does not include, fallbacks
  std::vector<RangeFlag> outside;       // where the duty leaves the calibrated range
};

Prediction predict(const ModelFile& model, const DutyCycle& duty, const PredictionOptions& options = {});

// A band at one output time.
struct BandAt {
  double value = 0, low = 0, high = 0;
};

// The predicted quantities at one output time.
struct PredictionMoment {
  std::string segment;
  std::size_t index = 0;  // into Prediction::time_s
  double time_s = 0;
  BandAt elongation_um;
  std::vector<BandAt> temperature_C;   // per Prediction::positions_m
  std::vector<BandAt> scale_error_um;  // per Prediction::scale_positions_m
};

// The moments a machine is measured at, computed once for the summary, prediction.json and
// prediction.html: the end of the duty, the largest elongation (by magnitude; the first if
// several), and each segment's last output time (a shift's end, the night's), in time order.
struct PredictionSummary {
  PredictionMoment end, largest;
  std::vector<PredictionMoment> segment_ends;
};
PredictionSummary summarize(const Prediction& p);

// Why a simulated rail predicts nothing real, or empty: a temperature or heat rate that is not
// finite, or a temperature beyond a rig's (units.hpp physical_range, to 1000 °C), where the
// friction law's heat runs away (its Stribeck term grows as the oil thins, and a coupled heat
// follows the rail). `inputs` names what drove it ("segment 1 (velocity_m_s = 3, …)").
std::string runaway_of(const RailSolution<double>& solution, const std::string& inputs);

// prediction.json (the summary's moments with their bands, the duty, the band's method and
// notes, the flags, the rail's profile at the end, the model's provenance; the series over time
// are prediction_time.csv's, which it names) and prediction_time.csv (time, segment, quantity,
// position, value, low, high: every output time).
std::string prediction_json(const Prediction& p, const DutyCycle& duty, const ModelFile& model,
                            const std::vector<std::string>& command);
std::string prediction_time_csv(const Prediction& p);
std::string prediction_summary(const Prediction& p);

// ∫_{a}^{b} α_th (T(x) − T_ref(x)) dx over a profile at ascending positions (a half-rail
// profile of x >= 0 is mirrored), trapezoidal between the nodes and linear at the ends, m.
double thermal_elongation_m(const std::vector<double>& x_m, const std::vector<double>& temperature_C,
                            const std::vector<double>& reference_C, double expansion_per_K, double a_m, double b_m);

}  // namespace lmcal
