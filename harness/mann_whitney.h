// The Mann-Whitney U test (Mann and Whitney 1947, "On a test of whether one of two random variables is
// stochastically larger than the other"): two-sided, exact for small samples without ties, else the normal
// approximation with the tie correction and a continuity correction (as R's wilcox.test and SciPy's
// mannwhitneyu compute it).
#pragma once

#include <cstddef>
#include <span>

namespace ab {

/// The result of one test.
struct MannWhitney {
  double u = 0.0;        ///< U of the first sample: pairs (x, y) with x > y, ties counting one half
  double p_value = 1.0;  ///< two-sided p-value
  bool exact = false;    ///< from the exact distribution of U (else the normal approximation)
};

/// Largest sample size for which the exact distribution is used (when there are no ties).
inline constexpr size_t kMannWhitneyExactMax = 20;

/// Tests whether x and y come from the same distribution. Either sample empty: U = 0, p = 1.
MannWhitney mann_whitney_u(std::span<const double> x, std::span<const double> y);

/// P(U <= u) under the null hypothesis for samples of sizes m and n without ties (exact).
double mann_whitney_exact_cdf(size_t m, size_t n, double u);

}  // namespace ab
