// A Ceres cost function over many independent rows, r_i = f(θ, i), differentiated
// automatically with ceres::Jet. Unlike ceres::AutoDiffCostFunction over all rows, it
// evaluates the functor row by row and writes each row's derivatives straight into the
// Jacobian: no array of output Jets, so a 10⁵-row fit stays within cache and time.
//
// The functor has two templated members — the same model code serves double (residuals
// only) and Jet (Jacobian):
//   template <typename T> Prepared<T> prepare(const T* theta) const;   // once per evaluation
//   template <typename T> T operator()(Prepared<T>& prepared, std::size_t row) const;
// `prepare` turns θ into the model's parameter structs once, so the row loop does not
// rebuild them (for Jets that copying is a large part of the cost).
// Up to 8 parameters use Jet<double, 8>, up to 12 Jet<double, 12>, up to 16 Jet<double, 16>.
#pragma once

#include <ceres/cost_function.h>
#include <ceres/jet.h>

#include <Eigen/Core>

#include <algorithm>
#include <array>
#include <vector>
#include <cmath>
#include <cstddef>
#include <optional>
#include <utility>

#include "lmcal/error.hpp"
#include "lmcal/fit/fit_result.hpp"
#include "parallel_slices.hpp"
#include "run_offsets.hpp"

namespace lmcal::detail {

// A robust loss applied row by row: r̃ = r · sqrt(ρ(r²) / r²), so that Σ r̃² = Σ ρ(r²) and a
// plain least-squares solver (Ceres, NLopt) minimises the robust cost of every row on its
// own. (A ceres::LossFunction on a batched block would act on the block's total instead.)
//   Huber:  ρ(s) = s for s <= δ², 2δ√s - δ² beyond;   Cauchy: ρ(s) = δ² ln(1 + s/δ²).
struct RowLoss {
  RobustLoss kind = RobustLoss::none;
  double scale = 1.0;  // δ, in units of the (whitened) residual
};

template <typename T>
T robust_residual(const T& r, const RowLoss& loss) {
  using std::abs;
  using std::log1p;
  using std::sqrt;
  const double d = loss.scale;
  switch (loss.kind) {
    case RobustLoss::none: return r;
    case RobustLoss::huber:
      if (abs(r) <= d) return r;
      return r * sqrt(2.0 * d / abs(r) - d * d / (r * r));
    case RobustLoss::cauchy: {
      const T s = r * r;
      if (s == 0.0) return r;
      return r * sqrt(d * d * log1p(s / (d * d)) / s);
    }
  }
  return r;
}

// A cost whose Gauss-Newton normal equations can be accumulated row by row, without
// storing its Jacobian (least_squares.cc then solves it by its own Levenberg-Marquardt):
// fills ½‖r‖², JᵀJ and Jᵀr at θ over all parameters. False when a residual is not finite.
// `held` (one flag per parameter, or empty for none): parameters the solver does not step; their
// rows and columns of JᵀJ and entries of Jᵀr may come out 0 (a Jet then carries the others'
// derivatives only), the rest are the same bits.
class NormalEquationsCost {
 public:
  virtual ~NormalEquationsCost() = default;
  virtual bool normal_equations(const double* theta, const std::vector<bool>& held, double& cost, Eigen::MatrixXd& JtJ,
                                Eigen::VectorXd& Jtr) const = 0;
  // r(θ) and J(θ) stored column-major (the layout the engine keeps), without Ceres' row-major
  // detour; the columns of `held` parameters may come out 0, as in normal_equations.
  virtual bool residuals_and_jacobian(const double* theta, const std::vector<bool>& held, Eigen::VectorXd& r,
                                      Eigen::MatrixXd& J) const = 0;
  // True when the solver should try each step with the normal equations themselves rather than
  // a residual pass first: where residuals alone cost nearly as much (a simulation carries
  // the derivatives along) and nearly every step is taken, the normal equations of the trial
  // are those of the next iteration.
  virtual bool normal_equations_at_trials() const { return false; }
};

// Sums of x xᵀ over rows x = [J_i, r_i], centred within groups the way
// BatchedAutoDiffCostFunction centres its residuals (x_i - c_g · mean_g(x)), accumulated in
// chunks of consecutive rows of one group: each chunk's co-moment about its own mean, built
// from blocks of rows (a block's co-moment by one rank-k update, merged by Chan's formula),
// then the chunk mean's share once the group's mean is known. Exact where a column is
// constant within a group, as a run's load is (the raw sums would cancel to rounding noise
// there), and fast: per row only a copy into the block.
class CentredSums {
 public:
  explicit CentredSums(Eigen::Index size)
      : size_(size), total_(Eigen::MatrixXd::Zero(size, size)), block_(kBlock, size) {}

  void add(std::size_t group, const double* x) {
    if (chunks_.empty() || chunks_.back().group != group) {
      flush();
      chunks_.push_back({group, 0, Eigen::VectorXd::Zero(size_)});
      if (group >= group_count_.size()) group_count_.resize(group + 1, 0.0), group_sum_.resize(group + 1, Eigen::VectorXd::Zero(size_));
    }
    for (Eigen::Index k = 0; k < size_; ++k) block_(rows_, k) = x[k];
    if (++rows_ == kBlock) flush();
  }

  // Σ (x - c_g m_g)(x - c_g m_g)ᵀ, `shrink` c_g per group (empty: no centring, c = 0). May be
  // called again with another `shrink`.
  Eigen::MatrixXd finish(const std::vector<double>& shrink) {
    close();
    Eigen::MatrixXd out = total_.selfadjointView<Eigen::Lower>();
    for (const Chunk& c : chunks_) {
      const double share = shrink.empty() ? 0.0 : shrink[c.group];
      const Eigen::VectorXd d = c.mean - share * group_sum_[c.group] / group_count_[c.group];
      out.noalias() += c.n * d * d.transpose();
    }
    return out;
  }

  // The rows `later` summed (the rows after this one's, not yet closed), appended: a chunk
  // that runs on across the seam merges with its continuation by Chan's formula.
  void append(CentredSums&& later) {
    LMCAL_ASSERT(!closed_ && !later.closed_ && later.size_ == size_, "append to open sums of one size");
    flush();
    later.flush();
    total_ += later.total_;
    std::size_t first = 0;
    if (!chunks_.empty() && !later.chunks_.empty() && chunks_.back().group == later.chunks_.front().group) {
      Chunk& c = chunks_.back();
      const Chunk& next = later.chunks_.front();
      const Eigen::VectorXd d = next.mean - c.mean;
      total_.selfadjointView<Eigen::Lower>().rankUpdate(d, c.n * next.n / (c.n + next.n));
      c.mean += d * (next.n / (c.n + next.n));
      c.n += next.n;
      first = 1;
    }
    for (std::size_t k = first; k < later.chunks_.size(); ++k) {
      const std::size_t group = later.chunks_[k].group;
      if (group >= group_count_.size()) group_count_.resize(group + 1, 0.0), group_sum_.resize(group + 1, Eigen::VectorXd::Zero(size_));
      chunks_.push_back(std::move(later.chunks_[k]));
    }
  }

  // Per group: rows and Σ x (after close(); groups beyond those seen have none).
  void close() {
    if (closed_) return;
    closed_ = true;
    flush();
    for (const Chunk& c : chunks_) {
      group_count_[c.group] += c.n;
      group_sum_[c.group] += c.n * c.mean;
    }
  }
  double group_count(std::size_t g) const { return g < group_count_.size() ? group_count_[g] : 0.0; }
  double group_sum(std::size_t g, Eigen::Index k) const { return g < group_sum_.size() ? group_sum_[g][k] : 0.0; }

 private:
  static constexpr Eigen::Index kBlock = 256;

  // The block's rows into the current chunk: M += M_b + n n_b / (n + n_b) (m_b - m)(m_b - m)ᵀ.
  void flush() {
    if (rows_ == 0) return;
    Chunk& c = chunks_.back();
    const auto n_b = static_cast<double>(rows_);
    auto rows = block_.topRows(rows_);
    // Shifted by the first row before the mean is taken: a column constant in the block is
    // then exactly 0 (a mean of equal values need not round back to the value).
    const Eigen::RowVectorXd shift = rows.row(0);
    rows.rowwise() -= shift;
    const Eigen::RowVectorXd m_shifted = rows.colwise().mean();
    rows.rowwise() -= m_shifted;
    total_.selfadjointView<Eigen::Lower>().rankUpdate(rows.transpose());
    const Eigen::VectorXd d = (shift + m_shifted).transpose() - c.mean;
    total_.selfadjointView<Eigen::Lower>().rankUpdate(d, c.n * n_b / (c.n + n_b));
    c.mean += d * (n_b / (c.n + n_b));
    c.n += n_b;
    rows_ = 0;
  }

  struct Chunk {
    std::size_t group;
    double n;
    Eigen::VectorXd mean;
  };
  Eigen::Index size_;
  Eigen::MatrixXd total_;  // lower triangle
  Eigen::MatrixXd block_;
  Eigen::Index rows_ = 0;
  bool closed_ = false;
  std::vector<Chunk> chunks_;
  std::vector<double> group_count_;
  std::vector<Eigen::VectorXd> group_sum_;
};

template <typename RowFunctor>
class BatchedAutoDiffCostFunction final : public ceres::CostFunction, public NormalEquationsCost {
 public:
  // `groups` (one id per row, optional): residuals and their derivatives are centred within
  // each group, r_i - c_g · mean_g(r), which profiles out one free offset per group (c_g = 1,
  // e.g. a load cell's zero per run) or whitens a random one (c_g = 1 - 1/sqrt(1 + n_g λ) for
  // an offset of variance λ σ²: generalised least squares). `shrink` holds c_g per group
  // (empty: 1 for all). Not combined with a robust loss. With `profiled` (rows: all of the
  // model's), λ is re-estimated at each evaluation of the normal equations while it profiles
  // (run_offsets.hpp) and `shrink` follows.
  BatchedAutoDiffCostFunction(RowFunctor functor, int num_parameters, std::size_t rows, RowLoss loss = {},
                              std::vector<std::size_t> groups = {}, std::vector<double> shrink = {},
                              ProfiledRunOffsets* profiled = nullptr)
      : functor_(std::move(functor)), rows_(rows), loss_(loss), groups_(std::move(groups)), shrink_(std::move(shrink)),
        profiled_(profiled) {
    LMCAL_ASSERT(groups_.empty() || (groups_.size() == rows && loss.kind == RobustLoss::none),
                 "group centring needs one group per row and no robust loss");
    LMCAL_ASSERT(num_parameters >= 1 && num_parameters <= 16, "1 to 16 parameters");
    mutable_parameter_block_sizes()->push_back(num_parameters);
    set_num_residuals(static_cast<int>(rows));
    find_stretches();
  }

  bool normal_equations(const double* theta, const std::vector<bool>& held, double& cost, Eigen::MatrixXd& JtJ,
                        Eigen::VectorXd& Jtr) const override {
    const int p = parameter_block_sizes()[0];
    std::optional<CentredSums> summed;
    const auto sums_of_part = [&] { return CentredSums(p + 1); };
    auto add = [&](CentredSums& part, std::size_t i, const double* gradient, double r) {
      double x[17];
      std::copy_n(gradient, p, x);
      x[p] = r;
      part.add(groups_.empty() ? 0 : groups_[i], x);
      return std::isfinite(r);
    };
    auto merge = [&](CentredSums&& part) {
      if (summed) summed->append(std::move(part));
      else summed.emplace(std::move(part));
    };
    if (!rows_with_gradient(theta, Reduce{sums_of_part, add, merge}, held)) return false;
    CentredSums& sums = summed ? *summed : summed.emplace(p + 1);  // (no rows: no parts)
    if (profiled_ && profiled_->profiling && !groups_.empty()) profile(sums, p);
    const Eigen::MatrixXd S = sums.finish(groups_.empty() ? std::vector<double>{} : shrink_or_ones());
    JtJ = S.topLeftCorner(p, p);
    Jtr = S.col(p).head(p);
    cost = 0.5 * S(p, p);
    return std::isfinite(cost);
  }

  bool residuals_and_jacobian(const double* theta, const std::vector<bool>& held, Eigen::VectorXd& r,
                              Eigen::MatrixXd& J) const override {
    const int p = parameter_block_sizes()[0];
    r.resize(static_cast<Eigen::Index>(rows_));
    J.resize(static_cast<Eigen::Index>(rows_), p);
    auto store = [&](Stored&, std::size_t i, const double* gradient, double value) {
      const auto row = static_cast<Eigen::Index>(i);
      r[row] = value;
      for (int j = 0; j < p; ++j) J(row, j) = gradient[j];
      return std::isfinite(value);
    };
    const bool ok = rows_with_gradient(theta, Reduce{[] { return Stored{}; }, store, [](Stored&&) {}}, held);
    if (ok && !groups_.empty()) centre_columns(r, J);
    return ok;
  }

  bool Evaluate(double const* const* parameters, double* residuals, double** jacobians) const override {
    const double* theta = parameters[0];
    bool ok = true;
    if (jacobians == nullptr || jacobians[0] == nullptr) {
      const auto prepared = functor_.prepare(theta);
      const int threads = slice_threads(rows_, kRowsPerThread);
      std::vector<OwnLine<decltype(functor_.prepare(theta))>> own(static_cast<std::size_t>(threads), {prepared});
      std::vector<char> finite(static_cast<std::size_t>(threads), 1);
      for_each_slice(rows_, threads, [&](int slice, std::size_t begin, std::size_t end) {
        auto& mine = own[static_cast<std::size_t>(slice)].prepared;
        for (std::size_t i = begin; i < end; ++i) {
          residuals[i] = robust_residual(functor_(mine, i), loss_);
          if (!std::isfinite(residuals[i])) {
            finite[static_cast<std::size_t>(slice)] = 0;
            return;
          }
        }
      });
      ok = std::find(finite.begin(), finite.end(), 0) == finite.end();
    } else {
      const auto p = static_cast<std::size_t>(parameter_block_sizes()[0]);
      auto store = [&](Stored&, std::size_t i, const double* gradient, double r) {
        residuals[i] = r;
        std::copy_n(gradient, p, jacobians[0] + i * p);
        return std::isfinite(r);
      };
      ok = rows_with_gradient(theta, Reduce{[] { return Stored{}; }, store, [](Stored&&) {}});
    }
    if (ok && !groups_.empty()) centre(residuals, jacobians ? jacobians[0] : nullptr);
    return ok;
  }

 private:
  // A functor may also give a row's residual and gradient in closed form (far cheaper than
  // Jets where the model is known):
  //   bool analytic() const;   // the closed form applies to this functor's parameters
  //   double gradient(Prepared<double>& prepared, std::size_t row, double* gradient) const;
  bool analytic() const {
    if constexpr (requires(const RowFunctor& f) { f.analytic(); }) return functor_.analytic();
    return false;
  }

  // A pass over the rows takes them in parts of kPart consecutive rows, each thread (of
  // parallel_slices.hpp) a stretch of consecutive parts: a part's rows are evaluated into a
  // buffer and added, in row order, to the part's own sums, and the parts' sums are then merged
  // in row order. A row's residual and gradient do not depend on the thread that computed it,
  // and the parts do not depend on the number of threads, so nor does anything summed from them:
  // the same bits with 1 thread or many. A pass is one parallel region (one barrier: on a loaded
  // machine a descheduled thread stalls the others at each), and the sums, a rank-k update per
  // block of rows, are accumulated on every thread (on the calling thread alone they were half
  // of a 10⁵-row pass).
  static constexpr std::size_t kPart = 4096;
  static constexpr std::size_t kRowsPerThread = 4096;

  // What a pass does with each row: part() opens a part's sums, add(sums, row, gradient,
  // residual) adds a row to them (false: the row is not finite, and the pass fails), merge(sums)
  // takes each part's in row order.
  template <typename Part, typename Add, typename Merge>
  struct Reduce {
    Part part;
    Add add;
    Merge merge;
  };
  template <typename Part, typename Add, typename Merge>
  Reduce(Part, Add, Merge) -> Reduce<Part, Add, Merge>;  // (clang before 17 deduces no aggregate's arguments)
  // The sums of a pass that stores each row where it belongs (nothing to merge).
  struct Stored {};

  // A thread's copy of the prepared parameters on cache lines of its own: a row writes into it
  // (the sample's viscosity), and a line shared with the next thread's copy would bounce.
  template <typename Prepared>
  struct alignas(128) OwnLine {
    Prepared prepared;
  };

  // Each row's residual and gradient (p values) through `reduce`; false when a row is not
  // finite. By the closed form where the functor has one, else by the smallest Jet that holds
  // the parameters not `held` (8, 12 or 16); a held parameter's derivative is 0 (a 9-parameter
  // trajectory fit holding two constants fits in the 8-wide Jet, a third cheaper per row).
  template <typename R>
  bool rows_with_gradient(const double* theta, const R& reduce, const std::vector<bool>& held = {}) const {
    if (analytic()) return analytic_rows(theta, reduce);
    const int p = parameter_block_sizes()[0];
    std::vector<int> seeded;  // the parameters a Jet slot carries, in order
    for (int j = 0; j < p; ++j)
      if (held.empty() || !held[static_cast<std::size_t>(j)]) seeded.push_back(j);
    if (seeded.size() <= 8) return jet_rows<8>(theta, seeded, reduce);
    if (seeded.size() <= 12) return jet_rows<12>(theta, seeded, reduce);
    return jet_rows<16>(theta, seeded, reduce);
  }

  // slice(prepared, begin, end, gradients, residuals) fills rows [begin, end) with each thread's
  // copy of `prepared` (a row may change it: the sample's viscosity).
  template <typename Prepared, typename Slice, typename R>
  bool in_parts(const Prepared& prepared, const Slice& slice, const R& reduce) const {
    using Sums = decltype(reduce.part());
    const auto p = static_cast<std::size_t>(parameter_block_sizes()[0]);
    const std::size_t parts = (rows_ + kPart - 1) / kPart;
    const int threads = std::min<int>(slice_threads(rows_, kRowsPerThread), static_cast<int>(std::max<std::size_t>(parts, 1)));
    std::vector<OwnLine<Prepared>> own(static_cast<std::size_t>(threads), {prepared});
    std::vector<std::optional<Sums>> sums(parts);
    std::vector<char> finite(parts, 1);
    for_each_slice(parts, threads, [&](int s, std::size_t first, std::size_t last) {
      Prepared& mine = own[static_cast<std::size_t>(s)].prepared;
      const std::size_t size = std::min(rows_, kPart);
      std::vector<double> g(size * p), r(size);
      for (std::size_t k = first; k < last; ++k) {
        const std::size_t begin = k * kPart, n = std::min(kPart, rows_ - begin);
        slice(mine, begin, begin + n, g.data(), r.data());
        Sums& part = sums[k].emplace(reduce.part());
        for (std::size_t i = 0; i < n && finite[k]; ++i) finite[k] = reduce.add(part, begin + i, g.data() + i * p, r[i]);
      }
    });
    if (std::find(finite.begin(), finite.end(), 0) != finite.end()) return false;
    for (auto& part : sums) reduce.merge(std::move(*part));
    return true;
  }

  template <typename R>
  bool analytic_rows(const double* theta, const R& reduce) const {
    if constexpr (requires(const RowFunctor& f, decltype(f.prepare(theta)) prepared, double* g) {
                    f.gradient(prepared, std::size_t{}, g);
                  }) {
      const auto p = static_cast<std::size_t>(parameter_block_sizes()[0]);
      auto slice = [&](auto& prepared, std::size_t begin, std::size_t end, double* g, double* r) {
        for (std::size_t i = begin; i < end; ++i, g += p) {
          double value = functor_.gradient(prepared, i, g);
          if (loss_.kind != RobustLoss::none) {  // r̃(r): the chain rule through a one-slot Jet
            const ceres::Jet<double, 1> w = robust_residual(ceres::Jet<double, 1>(value, 0), loss_);
            value = w.a;
            for (std::size_t j = 0; j < p; ++j) g[j] *= w.v[0];
          }
          *r++ = value;
        }
      };
      return in_parts(functor_.prepare(theta), slice, reduce);
    } else {
      (void)theta, (void)reduce;
      return false;
    }
  }

  // Slot k of the Jets carries parameter seeded[k]; the others are constants.
  template <int N>
  bool jet_rows(const double* theta, const std::vector<int>& seeded, const auto& reduce) const {
    using Jet = ceres::Jet<double, N>;
    const int p = parameter_block_sizes()[0];
    std::vector<Jet> t(static_cast<std::size_t>(p));
    for (int j = 0; j < p; ++j) t[static_cast<std::size_t>(j)] = Jet(theta[j]);
    for (std::size_t k = 0; k < seeded.size(); ++k) {
      const auto j = static_cast<std::size_t>(seeded[k]);
      t[j] = Jet(theta[j], static_cast<int>(k));
    }
    auto slice = [this, &seeded](auto& prepared, std::size_t begin, std::size_t end, double* g, double* r) {
      this->template jet_slice<N>(prepared, seeded, begin, end, g, r);  // `this` named: clang sees the capture used
    };
    return in_parts(functor_.prepare(t.data()), slice, reduce);
  }

  // Flattened: GCC otherwise leaves Eigen's Jet assignments out of line in the row loop (a
  // call per Jet operation); inlined, the 100 k-sample diagnosis's Jet<16> fits run 1.5x faster.
  template <int N, typename Prepared>
  [[gnu::flatten]] void jet_slice(Prepared& prepared, const std::vector<int>& seeded, std::size_t begin, std::size_t end,
                                  double* g, double* r) const {
    using Jet = ceres::Jet<double, N>;
    const auto p = static_cast<std::size_t>(parameter_block_sizes()[0]);
    const std::size_t q = seeded.size();
    for (std::size_t i = begin; i < end; ++i, g += p) {
      const Jet value = robust_residual(functor_(prepared, i), loss_);
      if (q == p) {
        for (std::size_t j = 0; j < p; ++j) g[j] = value.v[j];
      } else {
        std::fill_n(g, p, 0.0);
        for (std::size_t k = 0; k < q; ++k) g[seeded[k]] = value.v[k];
      }
      *r++ = value.a;
    }
  }

  // λ from the raw residuals' per-group sums (column p of the sums), and c_g from it.
  void profile(CentredSums& sums, int p) const {
    const std::size_t groups = profiled_->shrink->size();
    std::vector<double> count(groups), sum(groups);
    sums.close();
    for (std::size_t g = 0; g < groups; ++g) count[g] = sums.group_count(g), sum[g] = sums.group_sum(g, p);
    const double within = sums.finish(std::vector<double>(groups, 1.0))(p, p);
    profiled_->update(count, sum, within);
    shrink_ = *profiled_->shrink;
  }

  std::vector<double> shrink_or_ones() const {
    if (!shrink_.empty()) return shrink_;
    return std::vector<double>(*std::max_element(groups_.begin(), groups_.end()) + 1, 1.0);
  }

  // Consecutive rows of one group, [begin, end) (a run's samples are a stretch of the log).
  struct Stretch {
    std::size_t begin, end, group;
  };

  void find_stretches() {
    if (groups_.empty()) return;
    group_count_.assign(*std::max_element(groups_.begin(), groups_.end()) + 1, 0.0);
    for (std::size_t i = 0; i < rows_; ++i) {
      if (i == 0 || groups_[i] != groups_[i - 1]) stretches_.push_back({i, i, groups_[i]});
      stretches_.back().end = i + 1;
      group_count_[groups_[i]] += 1;
    }
  }

  // c_g = 0 for every group (a random offset of variance 0): the whitening is the identity.
  bool identity() const {
    return !shrink_.empty() && std::all_of(shrink_.begin(), shrink_.end(), [](double c) { return c == 0; });
  }

  // x_i − c_g · mean_g(x) for a residual or a Jacobian column (x[i · stride]), stretch by stretch;
  // each group's sum in row order.
  void centre_one(double* x, std::size_t stride, std::vector<double>& sum) const {
    std::fill(sum.begin(), sum.end(), 0.0);
    for (const Stretch& s : stretches_) {
      double total = sum[s.group];
      for (std::size_t i = s.begin; i < s.end; ++i) total += x[i * stride];
      sum[s.group] = total;
    }
    for (std::size_t g = 0; g < sum.size(); ++g) sum[g] *= (shrink_.empty() ? 1.0 : shrink_[g]) / group_count_[g];
    for (const Stretch& s : stretches_) {
      const double m = sum[s.group];
      for (std::size_t i = s.begin; i < s.end; ++i) x[i * stride] -= m;
    }
  }

  void centre(double* residuals, double* jacobian) const {
    if (identity()) return;
    const std::size_t p = static_cast<std::size_t>(parameter_block_sizes()[0]);
    std::vector<double> sum(group_count_.size());
    centre_one(residuals, 1, sum);
    for (std::size_t j = 0; jacobian && j < p; ++j) centre_one(jacobian + j, p, sum);
  }

  // centre() for a column-major J.
  void centre_columns(Eigen::VectorXd& r, Eigen::MatrixXd& J) const {
    if (identity()) return;
    std::vector<double> sum(group_count_.size());
    centre_one(r.data(), 1, sum);
    for (Eigen::Index j = 0; j < J.cols(); ++j) centre_one(J.col(j).data(), 1, sum);
  }

  RowFunctor functor_;
  std::size_t rows_;
  RowLoss loss_;
  std::vector<std::size_t> groups_;
  mutable std::vector<double> shrink_;  // follows profiled_ while it profiles
  ProfiledRunOffsets* profiled_;
  std::vector<Stretch> stretches_;
  std::vector<double> group_count_;
};

}  // namespace lmcal::detail
