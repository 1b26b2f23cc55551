#include "lmcal/fit/model_file.hpp"

#include <fmt/format.h>
#include <toml++/toml.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <sstream>

#include "lmcal/error.hpp"

namespace lmcal {

const ModelParameter* ModelFile::find(const std::string& name) const {
  for (const auto* list : {&friction_parameters, &thermal_parameters})
    for (const auto& p : *list)
      if (p.name == name) return &p;
  return nullptr;
}

namespace {

std::vector<ModelParameter> parameters_of(const FitResult& fit) {
  std::vector<ModelParameter> out;
  for (const auto& p : fit.parameters) {
    if (p.name.starts_with("offset ") || p.name.starts_with("heat_scale ") || p.name.starts_with("T0 ")) continue;  // per run
    const bool profile = p.interval == "profile";
    out.push_back({p.name, p.unit, p.value, p.se, profile ? p.profile_low : p.ci_low, profile ? p.profile_high : p.ci_high,
                   !p.free || p.held_unidentifiable});
  }
  return out;
}

std::string quoted(const std::string& s) {
  std::string out = "\"";
  for (char c : s) {
    if (c == '"' || c == '\\') out += '\\';
    out += c;
  }
  return out + "\"";
}

std::string number(double v) { return std::isnan(v) ? "nan" : std::isinf(v) ? (v > 0 ? "inf" : "-inf") : fmt::format("{}", v); }

std::string string_list(const std::vector<std::string>& items) {
  std::vector<std::string> q;
  for (const auto& i : items) q.push_back(quoted(i));
  return "[" + fmt::format("{}", fmt::join(q, ", ")) + "]";
}

void write_parameters(std::string& out, const char* table, const std::vector<ModelParameter>& parameters) {
  for (const auto& p : parameters)
    out += fmt::format("[[{}.parameter]]\nname = {}\nunit = {}\nvalue = {}\nse = {}\nci95 = [{}, {}]\nheld = {}\n\n", table,
                       quoted(p.name), quoted(p.unit), number(p.value), number(p.se), number(p.ci_low), number(p.ci_high),
                       p.held);
}

[[noreturn]] void fail(const std::string& file, const toml::source_region& where, const std::string& what) {
  throw InputError(file, static_cast<long>(where.begin.line), static_cast<long>(where.begin.column), what);
}

double number_at(const std::string& file, const toml::table& t, const char* key) {
  const toml::node* n = t.get(key);
  if (!n) fail(file, t.source(), fmt::format("expected a number '{}'", key));
  if (const auto* i = n->as_integer()) return static_cast<double>(i->get());
  if (const auto* f = n->as_floating_point()) return f->get();
  fail(file, n->source(), fmt::format("key '{}': expected a number", key));
}

std::string string_at(const std::string& file, const toml::table& t, const char* key) {
  const toml::node* n = t.get(key);
  const auto* s = n ? n->as_string() : nullptr;
  if (!s) fail(file, n ? n->source() : t.source(), fmt::format("expected a text '{}'", key));
  return s->get();
}

std::vector<std::string> strings_at(const std::string& file, const toml::table& t, const char* key) {
  std::vector<std::string> out;
  const toml::node* n = t.get(key);
  if (!n) return out;
  const auto* a = n->as_array();
  if (!a) fail(file, n->source(), fmt::format("key '{}': expected a list of texts", key));
  for (const auto& item : *a) {
    const auto* s = item.as_string();
    if (!s) fail(file, item.source(), fmt::format("key '{}': expected a text", key));
    out.push_back(s->get());
  }
  return out;
}

std::vector<ModelParameter> read_parameters(const std::string& file, const toml::table& t) {
  std::vector<ModelParameter> out;
  const toml::node* n = t.get("parameter");
  const auto* list = n ? n->as_array() : nullptr;
  if (!list) fail(file, n ? n->source() : t.source(), "expected [[...parameter]] tables");
  for (const auto& item : *list) {
    const auto* p = item.as_table();
    if (!p) fail(file, item.source(), "expected a parameter table");
    ModelParameter m;
    m.name = string_at(file, *p, "name");
    m.unit = p->get("unit") ? string_at(file, *p, "unit") : "";
    m.value = number_at(file, *p, "value");
    if (!std::isfinite(m.value)) fail(file, p->get("value")->source(), fmt::format("parameter '{}': expected a finite value", m.name));
    m.se = p->get("se") ? number_at(file, *p, "se") : NAN;
    if (const auto* ci = p->get("ci95") ? p->get("ci95")->as_array() : nullptr; ci && ci->size() == 2) {
      m.ci_low = ci->get(0)->value_or(NAN);
      m.ci_high = ci->get(1)->value_or(NAN);
    }
    m.held = p->get("held") && p->get("held")->value_or(false);
    out.push_back(m);
  }
  return out;
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
    m.friction_causes = fo.effects;
    m.friction_parameters = parameters_of(friction->fit);
    m.friction_covariance = friction->fit.uncertainty.method;
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
    for (const auto& p : m.thermal_parameters)
      if (p.name == "h_W_m2K") m.h_W_m2K = p.value;
      else if (p.name != "alpha") m.mechanism_parameters.emplace_back(p.name, p.value);
    m.thermal_covariance = thermal->joint.uncertainty.method;
    m.heat_uncertainty = thermal->heat_uncertainty;
  }
  return m;
}

std::string model_file_toml(const ModelFile& m) {
  std::string out =
      "# lmcal calibrated model: the published friction law and rail model with the causes the diagnoses\n"
      "# accepted, refitted to the measurements. Every parameter with its standard error and 95 % interval.\n"
      "# Use it: lmcal simulate friction --model FILE, lmcal simulate thermal --model FILE\n";
  out += fmt::format("kind = \"lmcal calibrated model\"\nlmcal_version = {}\nset = {}\ncommand = {}\n\n", quoted(m.lmcal_version),
                     quoted(m.set), string_list(m.command));
  for (const auto& [file, hash] : m.inputs) out += fmt::format("[[input]]\nfile = {}\nsha256 = {}\n\n", quoted(file), quoted(hash));
  if (m.has_friction) {
    out += fmt::format(
        "[friction]\n# the friction law (Eqs. 3-7) with these effects added\ncauses = {}\ncovariance = {}\n"
        "reference_temperature_C = {}\nviscosity40_mm2_s = {}\n\n",
        string_list(m.friction_causes), quoted(m.friction_covariance), number(m.constants.T_ref_C), number(m.constants.nu_ref_mm2_s));
    write_parameters(out, "friction", m.friction_parameters);
  }
  if (m.has_thermal) {
    out += fmt::format("[thermal]\n# the rail model (Eqs. 11-15) with these mechanisms added; alpha belongs to this source model\n"
                       "source = {}\nmechanisms = {}\ncovariance = {}\nheat_uncertainty = {}\n\n",
                       quoted(std::string(to_string(m.source))), string_list(m.mechanisms), quoted(m.thermal_covariance),
                       quoted(m.heat_uncertainty));
    write_parameters(out, "thermal", m.thermal_parameters);
  }
  return out;
}

ModelFile read_model_file(const std::filesystem::path& path) {
  const std::string file = path.string();
  std::ifstream in(path);
  if (!in) throw InputError(file, 0, 0, "cannot open the model file");
  std::stringstream text;
  text << in.rdbuf();
  toml::table root;
  try {
    root = toml::parse(text.str(), file);
  } catch (const toml::parse_error& e) {
    fail(file, e.source(), std::string(e.description()));
  }
  if (!root.get("kind") || string_at(file, root, "kind") != "lmcal calibrated model")
    fail(file, root.source(), "expected kind = \"lmcal calibrated model\" (a model.toml written by lmcal calibrate)");
  ModelFile m;
  m.lmcal_version = root.get("lmcal_version") ? string_at(file, root, "lmcal_version") : "";
  m.set = root.get("set") ? string_at(file, root, "set") : "";
  m.command = strings_at(file, root, "command");
  if (const auto* f = root.get("friction") ? root.get("friction")->as_table() : nullptr) {
    m.has_friction = true;
    m.friction_causes = strings_at(file, *f, "causes");
    m.friction_covariance = f->get("covariance") ? string_at(file, *f, "covariance") : "";
    if (f->get("reference_temperature_C")) m.constants.T_ref_C = number_at(file, *f, "reference_temperature_C");
    if (f->get("viscosity40_mm2_s")) m.constants.nu_ref_mm2_s = number_at(file, *f, "viscosity40_mm2_s");
    m.friction_parameters = read_parameters(file, *f);
    for (const auto& p : m.friction_parameters) {
      const auto c = std::find(kFrictionConstantNames.begin(), kFrictionConstantNames.end(), p.name);
      if (c != kFrictionConstantNames.end()) fittable_constant(m.constants, static_cast<std::size_t>(c - kFrictionConstantNames.begin())) = p.value;
      else if (const auto slot = find_friction_effect(p.name)) m.effects[*slot] = p.value;
      else fail(file, f->source(), fmt::format("unknown friction parameter '{}'", p.name));
    }
    validate(m.constants);
  }
  if (const auto* t = root.get("thermal") ? root.get("thermal")->as_table() : nullptr) {
    m.has_thermal = true;
    try {
      m.source = parse_source_model(string_at(file, *t, "source"));
    } catch (const InvalidParameter& e) {
      fail(file, t->get("source")->source(), e.what());
    }
    m.mechanisms = strings_at(file, *t, "mechanisms");
    const auto library = thermal_extension_library();
    for (const auto& name : m.mechanisms)
      if (std::none_of(library.begin(), library.end(), [&](auto& e) { return e.name == name; }))
        fail(file, t->get("mechanisms")->source(), fmt::format("unknown mechanism '{}'", name));
    m.thermal_covariance = t->get("covariance") ? string_at(file, *t, "covariance") : "";
    m.heat_uncertainty = t->get("heat_uncertainty") ? string_at(file, *t, "heat_uncertainty") : "";
    m.thermal_parameters = read_parameters(file, *t);
    bool alpha = false;
    for (const auto& p : m.thermal_parameters) {
      if (p.name == "alpha") m.alpha = p.value, alpha = true;
      else if (p.name == "h_W_m2K") m.h_W_m2K = p.value;
      else m.mechanism_parameters.emplace_back(p.name, p.value);
    }
    if (!alpha) fail(file, t->source(), "expected an 'alpha' parameter in [thermal]");
  }
  if (!m.has_friction && !m.has_thermal) fail(file, root.source(), "expected a [friction] or a [thermal] table");
  return m;
}

}  // namespace lmcal
