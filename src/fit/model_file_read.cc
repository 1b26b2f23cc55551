// model.toml read back (read_model_file): every table and key checked, an error naming the
// file, line and column of what is wrong and what was expected.
#include "lmcal/fit/model_file.hpp"

#include <fmt/format.h>
#include <toml++/toml.h>

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <cmath>

#include "io/input_file.hpp"
#include "io/toml_text.hpp"
#include "lmcal/error.hpp"
#include "lmcal/fit/statistics.hpp"
#include "lmcal/io/units.hpp"

namespace lmcal {

namespace {

[[noreturn]] void fail(const std::string& file, const toml::source_region& where, const std::string& what) {
  throw InputError(file, static_cast<long>(where.begin.line), static_cast<long>(where.begin.column), what);
}

std::string known_list(const std::vector<std::string>& names) {
  return names.empty() ? "none" : fmt::format("{}", fmt::join(names, ", "));
}

// Refuses a key of `t` that is not among `known` (a misspelt key would otherwise be ignored).
void only_keys(const std::string& file, const toml::table& t, const char* table, const std::vector<std::string>& known) {
  for (const auto& [key, node] : t)
    if (std::find(known.begin(), known.end(), key.str()) == known.end())
      fail(file, key.source(), fmt::format("unknown key '{}' in {}; expected {}", key.str(), table, known_list(known)));
}

// A number (an integer or a float, read as the double it is: value_or(NAN) would read a float).
double number_of(const std::string& file, const toml::node& n, const std::string& what) {
  if (const auto* i = n.as_integer()) return static_cast<double>(i->get());
  if (const auto* f = n.as_floating_point()) return f->get();
  fail(file, n.source(), what + ": expected a number");
}

double number_at(const std::string& file, const toml::table& t, const char* key) {
  const toml::node* n = t.get(key);
  if (!n) fail(file, t.source(), fmt::format("expected a number '{}'", key));
  return number_of(file, *n, fmt::format("key '{}'", key));
}

double finite_at(const std::string& file, const toml::table& t, const char* key) {
  const double v = number_at(file, t, key);
  if (!std::isfinite(v)) fail(file, t.get(key)->source(), fmt::format("key '{}': expected a finite number, found {}", key, v));
  return v;
}

// Refuses `value` (at `where`) outside [low, high]: a parameter beyond it makes the model
// describe nothing real (an h of 1e300 W/m²K pins the rail to the ambient).
void require_within(const std::string& file, const toml::source_region& where, const std::string& name, double value,
                    double low, double high, std::string_view unit) {
  if (!(value >= low && value <= high))
    fail(file, where, fmt::format("{} = {}: expected a value in [{:g}, {:g}]{}{}", name, value, low, high, unit.empty() ? "" : " ",
                                  unit));
}

// The number `key` of `t`, within the range of a rig's values of `quantity` (units.hpp).
double within_at(const std::string& file, const toml::table& t, const char* key, Quantity quantity) {
  const double v = finite_at(file, t, key);
  const PhysicalRange range = physical_range(quantity);
  require_within(file, t.get(key)->source(), key, v, range.low, range.high, range.unit);
  return v;
}

// Keys whose text is a description or a command line: line breaks and tabs allowed, never an
// escape. Every other text is a name.
bool is_free_text(std::string_view key) { return key == "command" || key == "covariance" || key == "heat_uncertainty"; }

std::string string_at(const std::string& file, const toml::table& t, const char* key) {
  const toml::node* n = t.get(key);
  const auto* s = n ? n->as_string() : nullptr;
  if (!s) fail(file, n ? n->source() : t.source(), fmt::format("expected a text '{}'", key));
  // Every text of a model file reaches terminals, JSON and the report: the one name check.
  if (auto problem = io::name_problem(s->get(), is_free_text(key))) fail(file, n->source(), fmt::format("{}: {}", key, *problem));
  return s->get();
}

// A list of texts, each with where it stands in the file; with `distinct`, a text listed twice
// is refused (a mechanism listed twice would be applied twice).
std::vector<std::pair<std::string, toml::source_region>> strings_at(const std::string& file, const toml::table& t,
                                                                    const char* key, bool distinct = true) {
  std::vector<std::pair<std::string, toml::source_region>> out;
  const toml::node* n = t.get(key);
  if (!n) return out;
  const auto* a = n->as_array();
  if (!a) fail(file, n->source(), fmt::format("key '{}': expected a list of texts", key));
  for (const auto& item : *a) {
    const auto* s = item.as_string();
    if (!s) fail(file, item.source(), fmt::format("key '{}': expected a text", key));
    if (auto problem = io::name_problem(s->get(), is_free_text(key)))
      fail(file, item.source(), fmt::format("key '{}': {}", key, *problem));
    for (const auto& done : out)
      if (distinct && done.first == s->get())
        fail(file, item.source(), fmt::format("key '{}': '{}' is listed twice", key, done.first));
    out.emplace_back(s->get(), item.source());
  }
  return out;
}

std::vector<std::string> names_of(const std::vector<std::pair<std::string, toml::source_region>>& items) {
  std::vector<std::string> out;
  for (const auto& item : items) out.push_back(item.first);
  return out;
}

// A parameter as read, with where its name and value stand.
struct ReadParameter {
  ModelParameter p;
  toml::source_region name_at, value_at;
};

std::vector<ReadParameter> read_parameters(const std::string& file, const toml::table& t, const char* table) {
  std::vector<ReadParameter> out;
  const toml::node* n = t.get("parameter");
  const auto* list = n ? n->as_array() : nullptr;
  if (!list) fail(file, n ? n->source() : t.source(), fmt::format("expected [[{}.parameter]] tables", table));
  for (const auto& item : *list) {
    const auto* p = item.as_table();
    if (!p) fail(file, item.source(), "expected a parameter table");
    only_keys(file, *p, "a parameter", {"name", "unit", "value", "se", "ci95", "held"});
    ReadParameter r;
    ModelParameter& m = r.p;
    m.name = string_at(file, *p, "name");
    r.name_at = p->get("name")->source();
    for (const auto& done : out)
      if (done.p.name == m.name) fail(file, r.name_at, fmt::format("parameter '{}' is given twice in [{}]", m.name, table));
    m.unit = p->get("unit") ? string_at(file, *p, "unit") : "";
    m.value = number_at(file, *p, "value");
    r.value_at = p->get("value")->source();
    if (!std::isfinite(m.value))
      fail(file, r.value_at, fmt::format("parameter '{}': expected a finite value, found {}", m.name, m.value));
    m.se = p->get("se") ? number_at(file, *p, "se") : NAN;  // NaN: not known (written as nan)
    if (const toml::node* ci = p->get("ci95")) {
      const auto* a = ci->as_array();
      if (!a || a->size() != 2) fail(file, ci->source(), fmt::format("parameter '{}': expected ci95 = [low, high]", m.name));
      m.ci_low = number_of(file, (*a)[0], fmt::format("parameter '{}', ci95", m.name));
      m.ci_high = number_of(file, (*a)[1], fmt::format("parameter '{}', ci95", m.name));
    }
    if (const toml::node* held = p->get("held")) {
      if (!held->is_boolean()) fail(file, held->source(), fmt::format("parameter '{}': expected held = true or false", m.name));
      m.held = held->value_or(false);
    }
    out.push_back(std::move(r));
  }
  return out;
}

// The tables of the array of tables `key` of `t` ([[name]] in messages); none when absent.
std::vector<const toml::table*> tables_at(const std::string& file, const toml::table& t, const char* key,
                                          const std::string& name) {
  std::vector<const toml::table*> out;
  const toml::node* n = t.get(key);
  if (!n) return out;
  const auto* list = n->as_array();
  if (!list) fail(file, n->source(), fmt::format("expected [[{}]] tables", name));
  for (const auto& item : *list) {
    const auto* table = item.as_table();
    if (!table) fail(file, item.source(), fmt::format("expected a [[{}]] table", name));
    out.push_back(table);
  }
  return out;
}

// A square matrix of finite numbers, n × n.
Eigen::MatrixXd read_matrix(const std::string& file, const toml::table& t, const char* key, std::size_t n,
                            const std::string& table) {
  const toml::node* node = t.get(key);
  const auto* rows = node ? node->as_array() : nullptr;
  if (!rows || rows->size() != n)
    fail(file, node ? node->source() : t.source(), fmt::format("[{}]: expected {} = [[...], ...], {} rows", table, key, n));
  Eigen::MatrixXd m(static_cast<Eigen::Index>(n), static_cast<Eigen::Index>(n));
  for (std::size_t i = 0; i < n; ++i) {
    const auto* row = (*rows)[i].as_array();
    if (!row || row->size() != n) fail(file, (*rows)[i].source(), fmt::format("[{}] {}: expected a row of {} numbers", table, key, n));
    for (std::size_t j = 0; j < n; ++j) {
      const double v = number_of(file, (*row)[j], fmt::format("[{}] {}", table, key));
      if (!std::isfinite(v)) fail(file, (*row)[j].source(), fmt::format("[{}] {}: expected a finite number", table, key));
      m(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(j)) = v;
    }
  }
  const double scale = m.diagonal().cwiseAbs().maxCoeff();
  if ((m - m.transpose()).cwiseAbs().maxCoeff() > 1e-9 * scale || (m.diagonal().array() < 0).any())
    fail(file, node->source(), fmt::format("[{}] {}: expected a covariance (symmetric, variances >= 0)", table, key));
  // Positive semidefinite, judged on the correlation matrix D^-1/2 C D^-1/2 (a zero variance
  // scaled by 1): its eigenvalues lie in [0, n] whatever the parameters' units, so one tolerance
  // serves every file. A covariance lmcal wrote carries round-off of n·eps·(its condition) there,
  // and a singular one (a parameter fixed by the others) an eigenvalue of about -1e-16; -1e-8 is
  // far above both and far below what moves a draw (a direction with variance 1e-8 of the
  // parameters' own). Below it, the draws' square root would clamp the negative directions and
  // the band could exclude the estimate.
  const Eigen::VectorXd d = m.diagonal().unaryExpr([](double v) { return v > 0 ? 1 / std::sqrt(v) : 1.0; });
  const Eigen::MatrixXd correlation = d.asDiagonal() * m * d.asDiagonal();
  const double smallest = Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(correlation, Eigen::EigenvaluesOnly).eigenvalues()(0);
  if (smallest < -1e-8)
    fail(file, node->source(),
         fmt::format("[{}] {}: not a covariance: it is not positive semidefinite (the smallest eigenvalue of its correlation "
                     "matrix is {:.3g}, of the matrix {:.3g}; at least -1e-8 expected): a parameter's covariances exceed "
                     "what its variances allow",
                     table, key, smallest,
                     Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(m, Eigen::EigenvaluesOnly).eigenvalues()(0)));
  return m;
}

// [<table>.covariance_matrix]: the covariance of named parameters of the table.
ModelCovariance read_covariance(const std::string& file, const toml::table& parent, const char* table,
                                const std::vector<ModelParameter>& parameters, Eigen::MatrixXd* given_heat) {
  ModelCovariance c;
  const toml::node* n = parent.get("covariance_matrix");
  if (!n) return c;
  const std::string name = fmt::format("{}.covariance_matrix", table);
  const auto* t = n->as_table();
  if (!t) fail(file, n->source(), fmt::format("expected a [{}] table", name));
  only_keys(file, *t, ("[" + name + "]").c_str(), given_heat ? std::vector<std::string>{"parameters", "matrix", "given_heat"}
                                                   : std::vector<std::string>{"parameters", "matrix"});
  for (const auto& [p, where] : strings_at(file, *t, "parameters")) {
    if (std::none_of(parameters.begin(), parameters.end(), [&](auto& q) { return q.name == p; }))
      fail(file, where, fmt::format("[{}]: '{}' is not a parameter of [{}]", name, p, table));
    c.parameters.push_back(p);
  }
  c.matrix = read_matrix(file, *t, "matrix", c.parameters.size(), name);
  if (given_heat && t->get("given_heat")) *given_heat = read_matrix(file, *t, "given_heat", c.parameters.size(), name);
  return c;
}

// [<table>.range]: quantity = [low, high].
std::vector<CalibratedRange> read_ranges(const std::string& file, const toml::table& parent, const char* table) {
  std::vector<CalibratedRange> out;
  const toml::node* n = parent.get("range");
  if (!n) return out;
  const auto* t = n->as_table();
  if (!t) fail(file, n->source(), fmt::format("expected a [{}.range] table", table));
  for (const auto& [key, value] : *t) {
    const auto* a = value.as_array();
    if (!a || a->size() != 2) fail(file, value.source(), fmt::format("[{}.range] {}: expected [low, high]", table, key.str()));
    CalibratedRange r{std::string(key.str()), number_of(file, (*a)[0], std::string(key.str())), number_of(file, (*a)[1], std::string(key.str()))};
    if (!(r.low <= r.high)) fail(file, value.source(), fmt::format("[{}.range] {}: expected low <= high", table, key.str()));
    out.push_back(std::move(r));
  }
  return out;
}

const ReadParameter* find_read(const std::vector<ReadParameter>& list, std::string_view name) {
  for (const auto& r : list)
    if (r.p.name == name) return &r;
  return nullptr;
}

// [[friction.term]]: the empirical terms, in order (term k's parameters are "termk" and,
// with a scale, "termk_scale"); returns those parameter names.
std::vector<std::string> read_terms(const std::string& file, const toml::table& f, ModelFile& m) {
  std::vector<std::string> names;
  const toml::node* n = f.get("term");
  if (!n) return names;
  const auto* list = n->as_array();
  if (!list) fail(file, n->source(), "expected [[friction.term]] tables");
  for (const auto& item : *list) {
    const auto* t = item.as_table();
    if (!t) fail(file, item.source(), "expected a [[friction.term]] table");
    only_keys(file, *t, "[[friction.term]]", {"symbol", "factors", "coefficient", "scale", "seen"});
    FrictionTerm term;
    for (const auto& [text, where] : strings_at(file, *t, "factors", false)) {
      const auto factor = parse_factor(text);
      if (!factor)
        fail(file, where, fmt::format("factor '{}': expected transform:covariate[:centre], e.g. \"decay:sliding_distance_m\"", text));
      term.factors.push_back(*factor);
    }
    const std::size_t k = m.friction_terms.size() + 1;
    if (const std::string problem = term_form_problem(term); !problem.empty()) fail(file, t->source(), problem);
    const std::string coefficient = fmt::format("term{}", k), scale = fmt::format("term{}_scale", k);
    if (string_at(file, *t, "coefficient") != coefficient)
      fail(file, t->get("coefficient")->source(), fmt::format("expected coefficient = \"{}\" (terms in order)", coefficient));
    names.push_back(coefficient);
    if (term.has_scale()) {
      if (!t->get("scale") || string_at(file, *t, "scale") != scale)
        fail(file, t->get("scale") ? t->get("scale")->source() : t->source(), fmt::format("expected scale = \"{}\"", scale));
      names.push_back(scale);
    }
    if (const toml::node* seen = t->get("seen")) {
      const auto* ranges = seen->as_array();
      if (!ranges) fail(file, seen->source(), "expected seen = [{ covariate, min, max }, ...]");
      for (const auto& r : *ranges) {
        const auto* range = r.as_table();
        if (!range) fail(file, r.source(), "expected { covariate = \"...\", min = ..., max = ... }");
        only_keys(file, *range, "a range", {"covariate", "min", "max"});
        const auto covariate = find_term_covariate(string_at(file, *range, "covariate"));
        if (!covariate) fail(file, range->get("covariate")->source(), "unknown covariate");
        term.seen.push_back({*covariate, number_at(file, *range, "min"), number_at(file, *range, "max")});
      }
    }
    m.friction_terms.push_back(std::move(term));
  }
  return names;
}

void set_term_parameter(std::vector<FrictionTerm>& terms, const std::string& name, double value) {
  for (std::size_t t = 0; t < terms.size(); ++t) {
    if (name == fmt::format("term{}", t + 1)) terms[t].coefficient = value;
    if (name == fmt::format("term{}_scale", t + 1)) terms[t].scale = value;
  }
}

// [friction]: the seven constants, the viscosity's reference point and the effects of the causes.
void read_friction(const std::string& file, const toml::table& f, ModelFile& m) {
  only_keys(file, f, "[friction]",
            {"causes", "covariance", "reference_temperature_C", "viscosity40_mm2_s", "parameter", "term",
             "covariance_matrix", "range", "law"});
  m.has_friction = true;
  if (f.get("law")) {
    m.friction_law = string_at(file, f, "law");
    if (m.friction_law != "constants" && m.friction_law != "combinations")
      fail(file, f.get("law")->source(), fmt::format("law = '{}': expected \"constants\" or \"combinations\"", m.friction_law));
  }
  const auto causes = strings_at(file, f, "causes");
  std::vector<std::string> effects;
  for (const auto& info : FrictionEffectLibrary::infos) effects.emplace_back(info.name);
  for (const auto& [name, where] : causes)
    if (!find_friction_effect(name))
      fail(file, where, fmt::format("unknown friction effect '{}' in causes; expected one of {}", name, known_list(effects)));
  m.friction_causes = names_of(causes);
  m.friction_covariance = f.get("covariance") ? string_at(file, f, "covariance") : "";
  if (f.get("reference_temperature_C")) m.constants.T_ref_C = within_at(file, f, "reference_temperature_C", Quantity::temperature);
  if (f.get("viscosity40_mm2_s")) m.constants.nu_ref_mm2_s = within_at(file, f, "viscosity40_mm2_s", Quantity::viscosity);
  const auto parameters = read_parameters(file, f, "friction");
  const std::vector<std::string> term_parameters = read_terms(file, f, m);
  const std::vector<std::string> constants(kFrictionConstantNames.begin(), kFrictionConstantNames.end());
  for (const auto& r : parameters) {
    const auto c = std::find(constants.begin(), constants.end(), r.p.name);
    const auto cause = std::find(m.friction_causes.begin(), m.friction_causes.end(), r.p.name);
    const auto term = std::find(term_parameters.begin(), term_parameters.end(), r.p.name);
    if (c != constants.end()) fittable_constant(m.constants, static_cast<std::size_t>(c - constants.begin())) = r.p.value;
    else if (cause != m.friction_causes.end()) {
      const FrictionEffectInfo& info = FrictionEffectLibrary::infos[*find_friction_effect(r.p.name)];
      require_within(file, r.value_at, r.p.name, r.p.value, info.lower, info.upper, info.unit);
      if (!info.dynamics) m.effects[*find_friction_effect(r.p.name)] = r.p.value;  // see model_file_of
    }
    else if (term != term_parameters.end()) set_term_parameter(m.friction_terms, r.p.name, r.p.value);
    else
      fail(file, r.name_at,
           fmt::format("unknown friction parameter '{}'; expected {}, an effect among causes ({}) or a term's ({})", r.p.name,
                       known_list(constants), known_list(m.friction_causes), known_list(term_parameters)));
  }
  std::vector<std::string> needed = constants;
  needed.insert(needed.end(), m.friction_causes.begin(), m.friction_causes.end());
  needed.insert(needed.end(), term_parameters.begin(), term_parameters.end());
  for (const auto& name : needed)
    if (!find_read(parameters, name)) fail(file, f.source(), fmt::format("expected a parameter '{}' in [friction]", name));
  try {
    validate(m.constants);
  } catch (const InvalidParameter& e) {
    const ReadParameter* r = find_read(parameters, e.parameter());
    const char* key = e.parameter() == "T_ref_C" ? "reference_temperature_C" : "viscosity40_mm2_s";
    fail(file, r ? r->value_at : f.get(key) ? f.get(key)->source() : f.source(), e.what());
  }
  for (auto& r : parameters) m.friction_parameters.push_back(std::move(r.p));
  m.friction_covariance_matrix = read_covariance(file, f, "friction", m.friction_parameters, nullptr);
  m.friction_range = read_ranges(file, f, "friction");
}

// [thermal]: α, h (optional), the source model and the mechanisms with their parameters.
void read_thermal(const std::string& file, const toml::table& t, ModelFile& m) {
  only_keys(file, t, "[thermal]",
            {"source", "mechanisms", "covariance", "heat_uncertainty", "reading_terms", "parameter", "covariance_matrix",
             "range", "between_runs", "heat_reference"});
  m.reading_terms = names_of(strings_at(file, t, "reading_terms", false));
  m.has_thermal = true;
  try {
    m.source = parse_source_model(string_at(file, t, "source"));
  } catch (const InvalidParameter& e) {
    fail(file, t.get("source")->source(), e.what());
  }
  const auto library = thermal_extension_library();
  std::vector<std::string> known;
  for (const auto& e : library) known.push_back(e.name);
  const auto mechanisms = strings_at(file, t, "mechanisms");
  std::vector<std::string> allowed = {"alpha", "h_W_m2K"};  // and the mechanisms' parameters
  for (const auto& [name, where] : mechanisms) {
    const auto e = std::find_if(library.begin(), library.end(), [&](auto& x) { return x.name == name; });
    if (e == library.end()) fail(file, where, fmt::format("unknown mechanism '{}'; expected one of {}", name, known_list(known)));
    if (e->source && *e->source != m.source)
      fail(file, where, fmt::format("mechanism '{}' selects the source model '{}', but source = \"{}\"", name,
                                    to_string(*e->source), to_string(m.source)));
    allowed.insert(allowed.end(), e->parameters.begin(), e->parameters.end());
  }
  m.mechanisms = names_of(mechanisms);
  m.thermal_covariance = t.get("covariance") ? string_at(file, t, "covariance") : "";
  m.heat_uncertainty = t.get("heat_uncertainty") ? string_at(file, t, "heat_uncertainty") : "";
  const auto parameters = read_parameters(file, t, "thermal");
  for (const auto& r : parameters) {
    if (std::find(allowed.begin(), allowed.end(), r.p.name) == allowed.end())
      fail(file, r.name_at,
           fmt::format("unknown thermal parameter '{}'; expected alpha, h_W_m2K or a parameter of the mechanisms ({})",
                       r.p.name, known_list(m.mechanisms)));
    if (r.p.name == "alpha") {
      if (!(r.p.value >= 0 && r.p.value <= 1))
        fail(file, r.value_at, fmt::format("alpha = {}: expected a value in [0, 1]", r.p.value));
      m.alpha = r.p.value;
    } else if (r.p.name == "h_W_m2K") {
      if (!(r.p.value > 0)) fail(file, r.value_at, fmt::format("h_W_m2K = {}: expected a value > 0", r.p.value));
      require_within(file, r.value_at, r.p.name, r.p.value, 0, kHeatTransferRange.high, kHeatTransferRange.unit);
      m.h_W_m2K = r.p.value;
    } else {
      // A mechanism's parameter: within the bounds its fit has (the library's).
      for (const auto& e : library)
        for (std::size_t j = 0; j < e.parameters.size() && j < e.parameter_bounds.size(); ++j)
          if (e.parameters[j] == r.p.name)
            require_within(file, r.value_at, r.p.name, r.p.value, e.parameter_bounds[j].first, e.parameter_bounds[j].second, "");
      m.mechanism_parameters.emplace_back(r.p.name, r.p.value);
    }
  }
  for (const auto& name : allowed)
    if (name != "h_W_m2K" && !find_read(parameters, name))
      fail(file, t.source(), fmt::format("expected a parameter '{}' in [thermal]", name));
  for (auto& r : parameters) m.thermal_parameters.push_back(std::move(r.p));
  m.thermal_covariance_matrix = read_covariance(file, t, "thermal", m.thermal_parameters, &m.thermal_covariance_given_heat);
  m.thermal_range = read_ranges(file, t, "thermal");
  if (const toml::node* n = t.get("between_runs")) {
    const auto* b = n->as_table();
    if (!b) fail(file, n->source(), "expected a [thermal.between_runs] table");
    only_keys(file, *b, "[thermal.between_runs]", {"alpha_sd"});
    m.alpha_between_run_sd = finite_at(file, *b, "alpha_sd");
    if (m.alpha_between_run_sd < 0) fail(file, b->get("alpha_sd")->source(), "alpha_sd: expected a value >= 0");
  }
  for (const toml::table* r : tables_at(file, t, "heat_reference", "thermal.heat_reference")) {
    only_keys(file, *r, "[[thermal.heat_reference]]",
              {"velocity_m_s", "load_N", "preload_um", "block_length_mm", "temperature_C", "viscosity40_mm2_s", "heat_rate_W"});
    HeatReference h;
    h.conditions = {.load_N = finite_at(file, *r, "load_N"),
                    .preload_um = finite_at(file, *r, "preload_um"),
                    .block_length_mm = finite_at(file, *r, "block_length_mm"),
                    .velocity_m_s = finite_at(file, *r, "velocity_m_s"),
                    .temperature_C = finite_at(file, *r, "temperature_C")};
    h.viscosity40_mm2_s = within_at(file, *r, "viscosity40_mm2_s", Quantity::viscosity);
    h.heat_rate_W = finite_at(file, *r, "heat_rate_W");
    require_within(file, r->get("heat_rate_W")->source(), "heat_rate_W", h.heat_rate_W, kHeatRateRange.low, kHeatRateRange.high,
                   kHeatRateRange.unit);
    try {
      validate(h.conditions);
    } catch (const InvalidParameter& e) {
      const toml::node* at = r->get(e.parameter());
      fail(file, at ? at->source() : r->source(), std::string("[[thermal.heat_reference]]: ") + e.what());
    }
    m.heat_references.push_back(h);
  }
}

}  // namespace

ModelFile read_model_file(const std::filesystem::path& path) {
  const std::string file = path.string();
  const std::string text = io::read_text_file(path, "the model file");
  toml::table root;
  try {
    root = toml::parse(text, file);
  } catch (const toml::parse_error& e) {
    fail(file, e.source(), std::string(e.description()));
  }
  constexpr const char* kKind = "lmcal calibrated model";
  const toml::node* kind = root.get("kind");
  if (!kind || kind->value_or(std::string_view{}) != kKind)
    fail(file, kind ? kind->source() : toml::source_region{{1, 1}, {1, 1}, {}},
         fmt::format("expected kind = \"{}\" (a model.toml written by lmcal calibrate)", kKind));
  only_keys(file, root, "the model file", {"kind", "lmcal_version", "set", "guide", "command", "input", "friction", "thermal"});
  ModelFile m;
  m.lmcal_version = root.get("lmcal_version") ? string_at(file, root, "lmcal_version") : "";
  // Another major version may mean other parameters or units: refused, not misread.
  const auto major = [](std::string_view version) { return version.substr(0, version.find('.')); };
  if (!m.lmcal_version.empty() && major(m.lmcal_version) != major(LMCAL_VERSION))
    fail(file, root.get("lmcal_version")->source(),
         fmt::format("lmcal_version = \"{}\": written by another major version of lmcal (this is {}); recalibrate with "
                     "this version",
                     m.lmcal_version, LMCAL_VERSION));
  m.set = root.get("set") ? string_at(file, root, "set") : "";
  m.guide = root.get("guide") ? string_at(file, root, "guide") : "";
  m.command = names_of(strings_at(file, root, "command", false));
  for (const toml::table* i : tables_at(file, root, "input", "input")) {
    only_keys(file, *i, "[[input]]", {"file", "sha256"});
    m.inputs.emplace_back(string_at(file, *i, "file"), string_at(file, *i, "sha256"));
  }
  for (const char* table : {"friction", "thermal"}) {
    const toml::node* n = root.get(table);
    if (!n) continue;
    const auto* t = n->as_table();
    if (!t) fail(file, n->source(), fmt::format("expected a [{}] table", table));
    if (table == std::string_view("friction")) read_friction(file, *t, m);
    else read_thermal(file, *t, m);
  }
  if (!m.has_friction && !m.has_thermal) fail(file, root.source(), "expected a [friction] or a [thermal] table");
  return m;
}

}  // namespace lmcal