// A friction effect: one mechanism the published law (friction.hpp, Eq. 7) leaves out, with
// one parameter that is neutral at `info.neutral` (shared/PHYSICS.md §1a and §7).
//
// Adding one is a new header in friction_effects/ plus its line (and include) in
// friction_effects.hpp. The virtual rig (`lmcal generate --effect NAME=VALUE`), the friction
// fit (`lmcal fit friction --effect NAME`), the heat rate of the thermal fit and
// `lmcal diagnose friction` all take the library from there. The header defines
//
//   struct Name {
//     static constexpr FrictionEffectInfo info{name, unit, description, neutral, lower, upper, scale};
//     static constexpr FrictionEffectStage stage = FrictionEffectStage::on_law;   // or on_total
//     template <typename P, typename C, typename B, typename Total, typename E>
//     static auto correction_N(const FrictionConstants<P>& k, const FrictionConditions<C>& c,
//                              const B& breakdown, const Total& total_N, const E& value);
//   };
//
// `correction_N` returns the force the effect adds, N. It is templated like the law itself, so
// the same code makes data in the rig and gives derivatives (ceres::Jet) in the fits.
//   on_law:   corrects the law's terms; `total_N` is the published law's total.
//   on_total: scales the result; `total_N` is the law with every on_law effect applied.
// Trap: at `value == neutral` the correction must be zero for every condition (the effects
// test checks it for the whole library), or a fit of another effect would carry it along.
//
// Shape parameters. An effect whose form needs more than its value (a ripple's period and
// phase, a pre-sliding distance) lists them as its parts: `static constexpr std::size_t kParts`
// library entries registered right after it, each with `info.part_of` naming it and no
// correction of its own. Its correction_N takes its value and then theirs; the overload with
// its value alone takes the parts at their `neutral` values (for a part: the value a fit starts
// from, since with the effect at its neutral value the parts change nothing). A fit of the
// effect fits its parts with it (with_effect_parts), a rig sets them by name
// (--effect position_ripple_period_m=0.006), and a diagnosis tries the effect and its parts as
// one cause, started from the current model's residuals where a start from the parts' neutral
// values would not converge (src/diagnose/cause_starts.hpp: a ripple's period from a
// periodogram).
#pragma once

#include "lmcal/export.hpp"

namespace LMCAL_API lmcal {

struct FrictionEffectInfo {
  const char* name;         // the parameter's name in fits, truth files and on the command line
  const char* unit;
  const char* description;  // the equation in words, for `lmcal generate effects` and reports
  double neutral;           // the published law
  double lower, upper;      // bounds of a fit
  double scale;             // a typical size (the neutral value is often zero), for fit scaling
  const char* measure = ""; // what to log to see it directly, or to tell it from a look-alike
  // A term of the drive's dynamics, not of friction: fitted with every trajectory log that
  // needs it (friction_fit.hpp, drive_effects), never a candidate cause of a diagnosis.
  bool dynamics = false;
  // A log column that must vary for the cause to show at all ("temperature_C", "load_N",
  // "direction"): its precondition. A diagnosis does not try it on a log where the column is
  // constant or was not given, and says so. (A look-alike that stays possible is a tie instead:
  // seal_drag_block beside seal_drag at one block length.)
  const char* varies = "";
  // A shape parameter of the named effect (its part): fitted, set and reported with it, never
  // a cause or an effect of its own.
  const char* part_of = "";
};

enum class FrictionEffectStage { on_law, on_total };

}  // namespace lmcal
