// The friction cost function with empirical terms: its own translation unit (friction_residual.hpp says why).
#include "friction_residual.hpp"

namespace lmcal::detail {

std::unique_ptr<ceres::CostFunction> term_cost_function(const FrictionData& data, const std::vector<std::size_t>& rows,
                                                        const std::vector<std::size_t>& effect_slots, int parameters,
                                                        std::size_t n, const RowLoss& loss, std::vector<std::size_t> groups) {
  return std::make_unique<BatchedAutoDiffCostFunction<FrictionResidual<true>>>(
      FrictionResidual<true>{&data, rows, effect_slots}, parameters, n, loss, std::move(groups), data.run_shrink,
      rows.empty() ? data.profiled : nullptr);
}

}  // namespace lmcal::detail
