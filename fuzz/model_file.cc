// read_model_file (how `lmcal simulate … --model` and `lmcal predict` read a model.toml that
// `lmcal calibrate` wrote) on fuzzed TOML: refused with an InputError at a line of the file, or
// read with every parameter finite and within the ranges docs/formats.md ("Model files and
// duties: finite or refused") gives — α in [0, 1], h in (0, 1e5] W/m²K, the heat references'
// numbers finite, their viscosity and heat rate within the rig's ranges — and every covariance
// a finite square matrix of its parameters. The model file's writer (model_file_toml) writes
// back only what it read, so the round trip is the same values read again.
#include "fuzz_support.hpp"

#include "lmcal/fit/model_file.hpp"

namespace {

using namespace lmcal::fuzz;
namespace io = lmcal::io;

void check_parameters(const std::vector<lmcal::ModelParameter>& parameters, std::string_view table) {
  for (const lmcal::ModelParameter& p : parameters) {
    finite(p.value, fmt::format("[{}] parameter '{}' value", table, io::printable(p.name)));
    printable_names({p.name}, "parameter name");
  }
}

void check_covariance(const Eigen::MatrixXd& m, std::size_t n, std::string_view what) {
  if (m.rows() != static_cast<Eigen::Index>(n) || m.cols() != static_cast<Eigen::Index>(n))
    finding(fmt::format("{}: a {} x {} matrix for {} parameters", what, m.rows(), m.cols(), n));
  for (Eigen::Index i = 0; i < m.size(); ++i) finite(m.data()[i], what);
}

void check_covariance(const lmcal::ModelCovariance& c, const std::vector<lmcal::ModelParameter>& parameters,
                      std::string_view what) {
  for (const std::string& name : c.parameters)
    if (std::none_of(parameters.begin(), parameters.end(), [&](auto& p) { return p.name == name; }))
      finding(fmt::format("{} names '{}', not a parameter of the table", what, io::printable(name)));
  check_covariance(c.matrix, c.parameters.size(), what);
}

void check_loaded(const lmcal::ModelFile& m) {
  if (!m.has_friction && !m.has_thermal) finding("a model file read without a [friction] or a [thermal] table");
  if (m.has_friction) {
    check_parameters(m.friction_parameters, "friction");
    const lmcal::FrictionConstants<double>& k = m.constants;
    for (const double v : {k.k1, k.k2, k.mu_st, k.v_st_m_s, k.mu_v, k.beta_per_K, k.f0, k.nu_ref_mm2_s, k.T_ref_C})
      finite(v, "friction constant");
    in_range({k.T_ref_C}, "reference_temperature_C", lmcal::physical_range(lmcal::Quantity::temperature));
    in_range({k.nu_ref_mm2_s}, "viscosity40_mm2_s", lmcal::physical_range(lmcal::Quantity::viscosity));
    for (const double v : m.effects.values) finite(v, "friction effect");
    for (const lmcal::FrictionTerm& t : m.friction_terms) {
      finite(t.coefficient, "friction term coefficient");
      finite(t.scale, "friction term scale");
    }
    check_covariance(m.friction_covariance_matrix, m.friction_parameters, "[friction.covariance_matrix] matrix");
  }
  if (m.has_thermal) {
    check_parameters(m.thermal_parameters, "thermal");
    if (!(m.alpha >= 0 && m.alpha <= 1)) finding(fmt::format("alpha = {} got past the loader", m.alpha));
    if (m.h_W_m2K && !(*m.h_W_m2K > 0 && *m.h_W_m2K <= lmcal::kHeatTransferRange.high))
      finding(fmt::format("h_W_m2K = {} got past the loader", *m.h_W_m2K));
    for (const auto& [name, v] : m.mechanism_parameters) finite(v, "mechanism parameter " + io::printable(name));
    check_covariance(m.thermal_covariance_matrix, m.thermal_parameters, "[thermal.covariance_matrix] matrix");
    if (m.thermal_covariance_given_heat.size() > 0)
      check_covariance(m.thermal_covariance_given_heat, m.thermal_covariance_matrix.parameters.size(),
                       "[thermal.covariance_matrix] given_heat");
    finite(m.alpha_between_run_sd, "alpha_sd");
    if (m.alpha_between_run_sd < 0) finding(fmt::format("alpha_sd = {} got past the loader", m.alpha_between_run_sd));
    for (const lmcal::HeatReference& h : m.heat_references) {
      const lmcal::FrictionConditions<double>& c = h.conditions;
      for (const double v : {c.load_N, c.preload_um, c.block_length_mm, c.velocity_m_s, c.temperature_C, h.viscosity40_mm2_s})
        finite(v, "heat_reference");
      in_range({h.viscosity40_mm2_s}, "heat_reference viscosity40_mm2_s", lmcal::physical_range(lmcal::Quantity::viscosity));
      finite(h.heat_rate_W, "heat_reference heat_rate_W");
      in_range({h.heat_rate_W}, "heat_reference heat_rate_W", lmcal::kHeatRateRange);
    }
  }
}

// The file written back reads to the same parameters and covariances.
void check_round_trip(const lmcal::ModelFile& m) {
  const fs::path file = write_file("roundtrip_model.toml", lmcal::model_file_toml(m));
  const lmcal::ModelFile back = reloaded([&] { return lmcal::read_model_file(file); }, "model_file_toml");
  for (const auto& [a, b, what] : {std::tuple(&m.friction_parameters, &back.friction_parameters, "friction parameters"),
                                   std::tuple(&m.thermal_parameters, &back.thermal_parameters, "thermal parameters")}) {
    expect_same(a->size() == b->size(), what, a->size());
    for (std::size_t i = 0; i < a->size(); ++i) {
      expect_same((*a)[i].name == (*b)[i].name, what, i);
      expect_same(same((*a)[i].value, (*b)[i].value), what, i);
    }
  }
  for (const auto& [a, b, what] : {std::tuple(&m.friction_covariance_matrix.matrix, &back.friction_covariance_matrix.matrix, "friction covariance"),
                                   std::tuple(&m.thermal_covariance_matrix.matrix, &back.thermal_covariance_matrix.matrix, "thermal covariance")}) {
    expect_same(a->size() == b->size(), what, static_cast<std::size_t>(a->size()));
    for (Eigen::Index i = 0; i < a->size(); ++i) expect_same(same(a->data()[i], b->data()[i]), what, static_cast<std::size_t>(i));
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const fs::path file = write_file("model.toml", as_text(data, size));
  const auto model = loaded_or_refused([&] { return lmcal::read_model_file(file); }, {file}, true);
  if (!model) return 0;
  check_loaded(*model);
  check_round_trip(*model);
  return 0;
}
