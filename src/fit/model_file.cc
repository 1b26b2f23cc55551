// model.toml made and written (model_file_of, model_file_toml); read back in model_file_read.cc.
#include "lmcal/fit/model_file.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "io/toml_text.hpp"
#include "lmcal/error.hpp"

namespace lmcal {

const ModelParameter* ModelFile::find(const std::string& name) const {
  for (const auto* list : {&friction_parameters, &thermal_parameters})
    for (const auto& p : *list)
      if (p.name == name) return &p;
  return nullptr;
}

namespace {

const CalibratedRange* range_in(const std::vector<CalibratedRange>& ranges, std::string_view quantity) {
  for (const auto& r : ranges)
    if (r.quantity == quantity) return &r;
  return nullptr;
}

}  // namespace

const CalibratedRange* ModelFile::friction_range_of(std::string_view q) const { return range_in(friction_range, q); }

void ModelFile::require_friction_scalings(std::string_view use) const {
  if (friction_law != "combinations") return;
  throw InvalidParameter("model", fmt::format("its friction law was fitted in combinations (the log gave no load, preload "
                                              "or block length), so it holds only for the calibrated setup and {} needs "
                                              "it at other conditions: calibrate from a log with load_N, preload_um and "
                                              "block_length_mm",
                                              use));
}
const CalibratedRange* ModelFile::thermal_range_of(std::string_view q) const { return range_in(thermal_range, q); }

namespace {

// The covariance of the model's free parameters (`parameters`, held ones left out), from a
// fit's full matrix (`full`, in the order of fit.parameters).
ModelCovariance covariance_of(const FitResult& fit, const std::vector<ModelParameter>& parameters, const Eigen::MatrixXd& full) {
  ModelCovariance c;
  std::vector<Eigen::Index> index;
  for (const auto& p : parameters) {
    if (p.held) continue;
    const auto at = std::find_if(fit.parameters.begin(), fit.parameters.end(), [&](auto& q) { return q.name == p.name; });
    if (at == fit.parameters.end()) continue;
    c.parameters.push_back(p.name);
    index.push_back(at - fit.parameters.begin());
  }
  const auto n = static_cast<Eigen::Index>(index.size());
  c.matrix.resize(n, n);
  for (Eigen::Index a = 0; a < n; ++a)
    for (Eigen::Index b = 0; b < n; ++b) c.matrix(a, b) = full(index[a], index[b]);
  if (!c.matrix.allFinite()) c = {};  // a failed covariance: none
  return c;
}

template <class Rows, class Get>
void add_range(std::vector<CalibratedRange>& out, const char* quantity, const Rows& rows, Get&& get) {
  double lo = INFINITY, hi = -INFINITY;
  for (const auto& row : rows) {
    const double v = get(row);
    if (!std::isfinite(v)) continue;
    lo = std::min(lo, v);
    hi = std::max(hi, v);
  }
  if (lo <= hi) out.push_back({quantity, lo, hi});
}

// τ of α from run to run: the per-run estimates' spread beyond their own SEs, when the runs'
// heterogeneity test found them to disagree (0 otherwise).
double alpha_between_run_sd(const ThermalFitResult& thermal) {
  const auto& het = thermal.joint.uncertainty.heterogeneity;
  const bool differ = std::any_of(het.begin(), het.end(), [](auto& h) { return h.parameter == "alpha" && h.significant; });
  if (!differ || thermal.per_run.size() < 2) return 0;
  std::vector<double> alphas;
  double se2 = 0;
  for (const auto& run : thermal.per_run) {
    const ParameterEstimate& a = run.parameter("alpha");
    if (!std::isfinite(a.value) || !std::isfinite(a.se)) continue;
    alphas.push_back(a.value);
    se2 += a.se * a.se;
  }
  if (alphas.size() < 2) return 0;
  const double sd = sample_standard_deviation(alphas);
  return std::sqrt(std::max(0.0, sd * sd - se2 / static_cast<double>(alphas.size())));
}

std::vector<ModelParameter> parameters_of(const FitResult& fit) {
  std::vector<ModelParameter> out;
  for (const auto& p : fit.parameters) {
    if (p.per_run) continue;
    const bool profile = p.interval == "profile";
    out.push_back({p.name, p.unit, p.value, p.se, profile ? p.profile_low : p.ci_low, profile ? p.profile_high : p.ci_high,
                   !p.free || p.held_unidentifiable});
  }
  return out;
}

// The shortest text that reads back as the same double (-0 keeps its sign: "-0" would be an integer).
std::string number(double v) {
  if (std::isnan(v)) return "nan";
  if (std::isinf(v)) return v > 0 ? "inf" : "-inf";
  if (v == 0 && std::signbit(v)) return "-0.0";
  return fmt::format("{}", v);
}

std::string string_list(const std::vector<std::string>& items) {
  std::vector<std::string> q;
  for (const auto& i : items) q.push_back(manifest::toml_string(i));
  return "[" + fmt::format("{}", fmt::join(q, ", ")) + "]";
}

void write_parameters(std::string& out, const char* table, const std::vector<ModelParameter>& parameters) {
  for (const auto& p : parameters)
    out += fmt::format("[[{}.parameter]]\nname = {}\nunit = {}\nvalue = {}\nse = {}\nci95 = [{}, {}]\nheld = {}\n\n", table,
                       manifest::toml_string(p.name), manifest::toml_string(p.unit), number(p.value), number(p.se), number(p.ci_low), number(p.ci_high),
                       p.held);
}

void write_matrix(std::string& out, const char* key, const Eigen::MatrixXd& m) {
  out += fmt::format("{} = [\n", key);
  for (Eigen::Index i = 0; i < m.rows(); ++i) {
    std::vector<std::string> row;
    for (Eigen::Index j = 0; j < m.cols(); ++j) row.push_back(number(m(i, j)));
    out += fmt::format("  [{}],\n", fmt::join(row, ", "));
  }
  out += "]\n";
}

void write_covariance(std::string& out, const char* table, const ModelCovariance& c, const Eigen::MatrixXd* given_heat) {
  if (c.empty()) return;
  out += fmt::format("[{}.covariance_matrix]\n# the quoted covariance of the free parameters (lmcal predict draws from it)\n"
                     "parameters = {}\n",
                     table, string_list(c.parameters));
  write_matrix(out, "matrix", c.matrix);
  if (given_heat && given_heat->size() > 0) {
    out += "# the same before the heat's uncertainty was added (for a prediction that draws the friction constants)\n";
    write_matrix(out, "given_heat", *given_heat);
  }
  out += "\n";
}

// In the order of the quantities' names, the order a TOML table reads back in.
void write_ranges(std::string& out, const char* table, std::vector<CalibratedRange> ranges) {
  if (ranges.empty()) return;
  std::sort(ranges.begin(), ranges.end(), [](auto& a, auto& b) { return a.quantity < b.quantity; });
  out += fmt::format("[{}.range]\n# the calibration data's span: a prediction beyond it extrapolates\n", table);
  for (const auto& r : ranges) out += fmt::format("{} = [{}, {}]\n", r.quantity, number(r.low), number(r.high));
  out += "\n";
}

}  // namespace

ModelFile model_file_of(const FrictionFitResult* friction, const FrictionFitOptions& fo, const ThermalFitResult* thermal,
                        const ThermalFitOptions& to) {
  ModelFile m;
  m.lmcal_version = LMCAL_VERSION;
  if (friction) {
    m.has_friction = true;
    m.constants = friction->constants();
    m.constants.T_ref_C = fo.start.T_ref_C;
    m.constants.nu_ref_mm2_s = fo.start.nu_ref_mm2_s;
    m.effects = friction->effects();
    // Every effect the fit carries: the options' and the drive's own (drive_effects: a
    // trajectory's moving mass, an incline's weight), which fit_friction adds.
    // The drive's dynamics are recorded, not applied: the model's friction is the guide's, and a
    // simulated or predicted speed has no acceleration or incline of the calibration's axis.
    for (std::size_t j = FrictionConstants<double>::kFittable; j < friction->fit.parameters.size(); ++j)
      if (const auto slot = find_friction_effect(friction->fit.parameters[j].name)) {
        m.friction_causes.push_back(friction->fit.parameters[j].name);
        if (FrictionEffectLibrary::infos[*slot].dynamics) m.effects[*slot] = FrictionEffectLibrary::infos[*slot].neutral;
      }
    if (friction->law.combination()) m.friction_law = "combinations";
    m.friction_terms = friction->terms;
    m.friction_parameters = parameters_of(friction->fit);
    m.friction_covariance = friction->fit.uncertainty.method;
    m.friction_covariance_matrix = covariance_of(friction->fit, m.friction_parameters, friction->fit.covariance);
    add_range(m.friction_range, "velocity_m_s", friction->conditions, [](auto& c) { return c.velocity_m_s; });
    add_range(m.friction_range, "load_N", friction->conditions, [](auto& c) { return c.load_N; });
    add_range(m.friction_range, "temperature_C", friction->conditions, [](auto& c) { return c.temperature_C; });
    add_range(m.friction_range, "preload_um", friction->conditions, [](auto& c) { return c.preload_um; });
  }
  if (thermal) {
    m.has_thermal = true;
    m.alpha = thermal->joint.parameter("alpha").value;
    m.source = to.source;
    for (const auto& name : to.extensions) {
      for (const auto& e : thermal_extension_library())
        if (e.name == name && e.source) m.source = *e.source;
    }
    m.mechanisms = to.extensions;
    m.thermal_parameters = parameters_of(thermal->joint);
    // The readings' empirical terms are not the rail's: their parameters stay in the fit's
    // files, their symbols here.
    std::vector<std::string> term_parameters;
    for (const auto& indices : thermal->sensor_term_parameters)
      for (std::size_t k : indices) term_parameters.push_back(thermal->joint.parameters[k].name);
    std::erase_if(m.thermal_parameters, [&](const ModelParameter& p) {
      return std::find(term_parameters.begin(), term_parameters.end(), p.name) != term_parameters.end();
    });
    for (const auto& term : to.sensor_terms) m.reading_terms.emplace_back(to_string(term.kind));
    // h held at the fit's value is part of the model too (simulate with the h α was fitted with).
    if (std::none_of(m.thermal_parameters.begin(), m.thermal_parameters.end(), [](auto& p) { return p.name == "h_W_m2K"; }))
      m.thermal_parameters.push_back({"h_W_m2K", "W/m2K", to.h_W_m2K, 0, to.h_W_m2K, to.h_W_m2K, true});
    for (const auto& p : m.thermal_parameters)
      if (p.name == "h_W_m2K") m.h_W_m2K = p.value;
      else if (p.name != "alpha") m.mechanism_parameters.emplace_back(p.name, p.value);
    m.thermal_covariance = thermal->joint.uncertainty.method;
    m.heat_uncertainty = thermal->heat_uncertainty;
    m.thermal_covariance_matrix = covariance_of(thermal->joint, m.thermal_parameters, thermal->joint.covariance);
    const Eigen::MatrixXd& given = thermal->joint.uncertainty.covariance_given_input;
    if (given.size() > 0 && !m.thermal_covariance_matrix.empty())
      m.thermal_covariance_given_heat = covariance_of(thermal->joint, m.thermal_parameters, given).matrix;
    m.alpha_between_run_sd = alpha_between_run_sd(*thermal);
    if (std::all_of(thermal->runs.begin(), thermal->runs.end(), [](auto& r) { return r.heat_conditions.has_value(); }))
      for (const auto& r : thermal->runs) m.heat_references.push_back({*r.heat_conditions, r.heat_viscosity40_mm2_s, r.heat_rate_W});
    add_range(m.thermal_range, "velocity_m_s", thermal->runs, [](auto& r) { return r.velocity_m_s; });
    add_range(m.thermal_range, "load_N", thermal->runs, [](auto& r) { return r.load_N; });
    add_range(m.thermal_range, "temperature_C", thermal->samples, [](auto& s) { return s.measured_C; });
  }
  return m;
}

std::string model_file_toml(const ModelFile& m) {
  std::string out =
      "# lmcal calibrated model: the published friction law and rail model with the causes the diagnoses\n"
      "# accepted, refitted to the measurements. Every parameter with its standard error and 95 % interval.\n"
      "# Use it: lmcal simulate friction --model FILE, lmcal simulate thermal --model FILE\n";
  out += fmt::format("kind = \"lmcal calibrated model\"\nlmcal_version = {}\nset = {}\n", manifest::toml_string(m.lmcal_version),
                     manifest::toml_string(m.set));
  if (!m.guide.empty()) out += fmt::format("guide = {}\n", manifest::toml_string(m.guide));
  out += fmt::format("command = {}\n\n", string_list(m.command));
  for (const auto& [file, hash] : m.inputs) out += fmt::format("[[input]]\nfile = {}\nsha256 = {}\n\n", manifest::toml_string(file), manifest::toml_string(hash));
  if (m.has_friction) {
    out += fmt::format(
        "[friction]\n# the friction law (Eqs. 3-7) with these effects added\ncauses = {}\ncovariance = {}\n"
        "reference_temperature_C = {}\nviscosity40_mm2_s = {}\n\n",
        string_list(m.friction_causes), manifest::toml_string(m.friction_covariance), number(m.constants.T_ref_C), number(m.constants.nu_ref_mm2_s));
    if (m.friction_law != "constants")
      out += fmt::format("# fitted without load, preload and block length: holds for the calibrated setup only\nlaw = {}\n\n",
                         manifest::toml_string(m.friction_law));
    write_parameters(out, "friction", m.friction_parameters);
    for (std::size_t t = 0; t < m.friction_terms.size(); ++t) {
      const FrictionTerm& term = m.friction_terms[t];
      std::vector<std::string> factors, seen;
      for (const auto& f : term.factors) factors.push_back(factor_text(f));
      for (const auto& r : term.seen)
        seen.push_back(fmt::format("{{ covariate = {}, min = {}, max = {} }}", manifest::toml_string(term_covariate_name(r.covariate)),
                                   number(r.min), number(r.max)));
      out += fmt::format(
          "[[friction.term]]\n# empirical: learned from the residuals, not a named cause; beyond `seen` an "
          "extrapolation\nsymbol = {}\nfactors = {}\ncoefficient = {}\n",
          manifest::toml_string(term.symbol(t + 1)), string_list(factors), manifest::toml_string(fmt::format("term{}", t + 1)));
      if (term.has_scale()) out += fmt::format("scale = {}\n", manifest::toml_string(fmt::format("term{}_scale", t + 1)));
      out += fmt::format("seen = [{}]\n\n", fmt::join(seen, ", "));
    }
    write_covariance(out, "friction", m.friction_covariance_matrix, nullptr);
    write_ranges(out, "friction", m.friction_range);
  }
  if (m.has_thermal) {
    out += fmt::format("[thermal]\n# the rail model (Eqs. 11-15) with these mechanisms added; alpha belongs to this source model\n"
                       "source = {}\nmechanisms = {}\ncovariance = {}\nheat_uncertainty = {}\n",
                       manifest::toml_string(std::string(to_string(m.source))), string_list(m.mechanisms), manifest::toml_string(m.thermal_covariance),
                       manifest::toml_string(m.heat_uncertainty));
    if (!m.reading_terms.empty())
      out += "# fitted with an empirical term on the thermocouple readings (learned from the residuals, not a named\n"
             "# cause): it describes the readings, not the rail, and is not applied when the rail is simulated\n"
             "reading_terms = " + string_list(m.reading_terms) + "\n";
    out += "\n";
    write_parameters(out, "thermal", m.thermal_parameters);
    write_covariance(out, "thermal", m.thermal_covariance_matrix, &m.thermal_covariance_given_heat);
    write_ranges(out, "thermal", m.thermal_range);
    out += fmt::format("[thermal.between_runs]\n# the spread of alpha from run to run beyond the runs' own noise (0: none found)\n"
                       "alpha_sd = {}\n\n",
                       number(m.alpha_between_run_sd));
    for (const auto& r : m.heat_references)
      out += fmt::format("[[thermal.heat_reference]]\n# a calibration run's heat: the friction law at these conditions\n"
                         "velocity_m_s = {}\nload_N = {}\npreload_um = {}\nblock_length_mm = {}\ntemperature_C = {}\n"
                         "viscosity40_mm2_s = {}\nheat_rate_W = {}\n\n",
                         number(r.conditions.velocity_m_s), number(r.conditions.load_N), number(r.conditions.preload_um),
                         number(r.conditions.block_length_mm), number(r.conditions.temperature_C),
                         number(r.viscosity40_mm2_s), number(r.heat_rate_W));
  }
  return out;
}

std::string calibrated_guide(const ThermalDataSet& data) {
  if (data.runs.empty()) return "";
  for (const auto& run : data.runs)
    if (run.guide != data.runs.front().guide) return "";
  return data.runs.front().guide;
}

}  // namespace lmcal
