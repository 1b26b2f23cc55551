// Private: fleet.html, the fleet's summary as one self-contained page (fleet_summary.hpp).
#pragma once

#include <string>

#include "lmcal/fleet/fleet_summary.hpp"

namespace lmcal {

std::string fleet_report_html(const FleetSummary& summary);

}  // namespace lmcal
