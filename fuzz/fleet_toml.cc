// discover_fleet (how `lmcal fleet ROOT` finds its sets) on a fuzzed ROOT/fleet.toml, in a
// folder of this process's own that holds two measurement folders (u1/ and u2/2026-09-01/, each
// with the companion friction.csv) and, beside ROOT, the companion files (a folder outside ROOT
// that holds measurements: "../" from ROOT). Each input is discovered twice, as `lmcal fleet`
// does and with --allow-outside-root. Refused with an InputError at a line of fleet.toml (or
// about ROOT as a whole: no sets), or every set found has an id fit for outputs — it passes the
// name check, does not climb ("..") and is not absolute, so that OUT/<id> stays under OUT —
// unique, and a folder that resolves inside ROOT, unless the id is "outside/…", which only
// --allow-outside-root makes, for a folder that resolves outside.
#include "fuzz_support.hpp"

#include "lmcal/fleet/fleet.hpp"
#include "lmcal/io/date.hpp"

namespace {

using namespace lmcal::fuzz;
namespace io = lmcal::io;

// ROOT, with its measurement folders, made once per process.
const fs::path& fleet_root() {
  static const fs::path root = [] {
    copy_companions();
    const fs::path r = work_dir() / "fleet";
    for (const char* set : {"u1", "u2/2026-09-01"}) {
      fs::create_directories(r / set);
      fs::copy_file(work_dir() / "friction.csv", r / set / "friction.csv", fs::copy_options::overwrite_existing);
    }
    return r;
  }();
  return root;
}

bool resolves_inside(const fs::path& path, const fs::path& root) {
  const fs::path relative = fs::weakly_canonical(path).lexically_relative(fs::weakly_canonical(root));
  return !relative.empty() && *relative.begin() != "..";
}

void check_loaded(const lmcal::Fleet& fleet, bool allow_outside) {
  if (fleet.sets.empty()) finding("a fleet without sets got past discover_fleet");
  for (const lmcal::FleetSet& s : fleet.sets) {
    const std::string id = io::printable(s.id);
    printable_names({s.id}, "set id");
    printable_names({s.unit, s.axis, s.machine}, fmt::format("set {}'s unit, axis or machine", id));
    if (s.id.empty() || s.id.starts_with("..") || fs::path(s.id).is_absolute())
      finding(fmt::format("set id '{}' would name outputs outside the output folder", id));
    if (!s.date.empty() && !lmcal::io::parse_iso_date(s.date)) finding(fmt::format("set {}'s date '{}' is not a day", id, io::printable(s.date)));
    const bool inside = resolves_inside(s.dir, fleet.root);
    if (s.id.starts_with("outside/")) {
      if (!allow_outside) finding(fmt::format("set {} outside ROOT without --allow-outside-root", id));
      if (inside) finding(fmt::format("set {} is named outside but its folder {} lies inside ROOT", id, io::printable(s.dir.string())));
    } else if (!inside) {
      finding(fmt::format("set {}'s folder {} resolves outside ROOT", id, io::printable(s.dir.string())));
    }
    if (std::count_if(fleet.sets.begin(), fleet.sets.end(), [&](const lmcal::FleetSet& o) { return o.id == s.id; }) != 1)
      finding(fmt::format("set id {} is given to two sets", id));
  }
}

// (a) and (b) as loaded_or_refused, but a refusal may also be about ROOT as a whole (no sets).
std::optional<lmcal::Fleet> discovered_or_refused(const fs::path& root, const fs::path& file, bool allow_outside) {
  try {
    return lmcal::discover_fleet(root, {}, allow_outside);
  } catch (const lmcal::InputError& e) {
    if (e.file() != root.string()) check_refusal(e, {file}, true);
  } catch (const std::exception& e) {
    finding(fmt::format("{} escaped discover_fleet: {}", type_name(typeid(e)), e.what()));
  } catch (...) {
    finding("an exception not derived from std::exception escaped discover_fleet");
  }
  return std::nullopt;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const fs::path& root = fleet_root();
  const fs::path file = write_file("fleet/fleet.toml", as_text(data, size));
  for (const bool allow_outside : {false, true})
    if (const auto fleet = discovered_or_refused(root, file, allow_outside)) check_loaded(*fleet, allow_outside);
  return 0;
}
