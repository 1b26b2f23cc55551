// lmcal simulate: the physics core on its own, without measurements.
#include "cli_common.hpp"

namespace lmcal::cli {

void setup_simulate(CLI::App& app, const std::vector<std::string>& argv) {
  CLI::App* simulate = app.add_subcommand("simulate", "Run the friction law or the rail thermal model");
  simulate->require_subcommand(1);
  setup_simulate_friction(*simulate, argv);
  setup_simulate_thermal(*simulate, argv);
}

}  // namespace lmcal::cli
