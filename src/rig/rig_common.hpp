// Shared by the virtual rig's generators (private to src/rig): reproducible random numbers,
// sensor noise with memory, and the truth file's common parts.
#pragma once

#include <cmath>
#include <cstdint>
#include <numbers>
#include <random>
#include <string>
#include <vector>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "io/toml_text.hpp"
#include "lmcal/error.hpp"

#include "lmcal/rig/virtual_rig.hpp"

namespace lmcal::rig {

// Reproducible random numbers: mt19937_64's sequence is fixed by the standard, and the
// transforms below are ours (std::normal_distribution differs between libraries).
class Rng {
 public:
  explicit Rng(std::uint64_t seed) : engine_(seed) {}
  double uniform() { return static_cast<double>(engine_() >> 11) * 0x1.0p-53; }  // [0, 1)
  double uniform(double lo, double hi) { return lo + (hi - lo) * uniform(); }
  double normal() {  // Box-Muller
    const double u1 = 1.0 - uniform(), u2 = uniform();
    return std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * std::numbers::pi * u2);
  }

 private:
  std::mt19937_64 engine_;
};

// Independent streams per run from one seed (splitmix64).
inline std::uint64_t derive_seed(std::uint64_t seed, std::uint64_t stream) {
  std::uint64_t z = seed + 0x9E3779B97F4A7C15ull * (stream + 1);
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  return z ^ (z >> 31);
}

// The random numbers of the later options (heat_factor, the gain error) come from a
// generator of their own, so the per-run streams above, and every data set made without
// these options, stay as they were.
constexpr std::uint64_t kLaterStreamKey = 0x6A09E667F3BCC909ull;
// The phase of the daily ambient swing of each run (its start in the day): a stream of its own.
constexpr std::uint64_t kDailyStreamKey = 0xBB67AE8584CAA73Bull;

// Sensor noise with memory: an AR(1) series of marginal σ and lag-1 autocorrelation φ,
// e_0 = σ z_0, e_t = φ e_{t-1} + sqrt(1 − φ²) σ z_t. The caller draws the white z_t, so the
// stream is the same for any φ, and φ = 0 gives σ z_t exactly (the bytes of old data).
class Ar1Noise {
 public:
  Ar1Noise(double sigma, double phi) : sigma_(sigma), phi_(phi), innovation_(std::sqrt(1 - phi * phi)) {}
  double next(double z) {
    unit_ = started_ ? phi_ * unit_ + innovation_ * z : z;
    started_ = true;
    return sigma_ * unit_;
  }

 private:
  double sigma_, phi_, innovation_;
  double unit_ = 0;  // e_t / σ
  bool started_ = false;
};

// 1 + relative_sigma · z, refused when it is not > 0 (no negative heat or gain).
inline double positive_factor(const char* parameter, double relative_sigma, double z, const std::string& what) {
  const double factor = 1 + relative_sigma * z;
  if (!(factor > 0)) {
    throw InvalidParameter(parameter, relative_sigma,
                           fmt::format("small enough that 1 + {}·z > 0 ({}; this seed drew z = {:.3f})", parameter,
                                       what, z));
  }
  return factor;
}

// Rounds to `decimals` places; dividing the integer by a power of ten gives the double
// nearest to the decimal, so the CSV shows "22.08", not "22.080000000000002".
inline double round_to(double value, int decimals) {
  const double scale = std::pow(10.0, decimals);
  return std::round(value * scale) / scale;
}

// A raw run's [[run]] table in the friction manifest: its file ("friction/<id>.csv", returned in
// `file`) and its conditions as keys. A user's guide (`block_length_key`) has its block length
// written out, as the built-in catalog cannot supply it.
inline std::string raw_run_manifest_toml(const std::string& id, const std::string& guide, const FrictionConditions<double>& c,
                                         double viscosity40_mm2_s, bool block_length_key, std::string& file) {
  file = fmt::format("friction/{}.csv", id);
  std::string toml = fmt::format(
      "\n[[run]]\nid = {}\nfile = {}\nguide = {}\nload_N = {}\npreload_um = {}\ntemperature_C = {}\n"
      "viscosity40_mm2_s = {}\n",
      manifest::toml_string(id), manifest::toml_string(file), manifest::toml_string(guide), c.load_N, c.preload_um,
      c.temperature_C, viscosity40_mm2_s);
  if (block_length_key) toml += fmt::format("block_length_mm = {}\n", c.block_length_mm);
  return toml;
}

// Every named effect with its value, unit and whether it is on (the truth file's "effects").
// One run of a raw generator: its guide and conditions (the block length from the catalog).
struct RunSetup {
  const GuideSpec* spec;
  FrictionConditions<double> conditions;
};
// Every run of `config` in the order the raw generators number them (run01, run02, …): repeats
// outermost, then guides, preloads, loads and temperatures.
inline std::vector<RunSetup> run_setups(const FrictionRigConfig& config) {
  std::vector<RunSetup> out;
  for (int repeat = 0; repeat < config.runs; ++repeat)
    for (const auto& model : config.guides)
      for (double pc : config.preload_um)
        for (double P : config.load_N)
          for (double T : config.temperature_C) {
            const GuideSpec& spec = find_guide(model, config.catalog);
            out.push_back({&spec, {.load_N = P, .preload_um = pc,
                                   .block_length_mm = require(spec, &GuideSpec::block_length_mm, "block_length_mm"),
                                   .temperature_C = T}});
          }
  return out;
}

nlohmann::json effects_json(const RigEffects& effects);
// The friction constants by name (the truth file's "friction_constants").
nlohmann::json constants_json(const FrictionConstants<double>& k);

// InvalidParameter naming --effect when a thermal effect is on: a friction log does not see it.
void require_no_thermal_effects(const RigEffects& effects);

}  // namespace lmcal::rig
