#include "harness/mann_whitney.h"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <vector>

namespace ab {

namespace {

/// Mid-ranks (1-based) of the pooled samples, and the tie term sum(t^3 - t) over groups of equal values.
std::vector<double> mid_ranks(const std::vector<double>& pooled, double& tie_term) {
  std::vector<size_t> order(pooled.size());
  std::iota(order.begin(), order.end(), size_t{0});
  std::sort(order.begin(), order.end(), [&](size_t a, size_t b) { return pooled[a] < pooled[b]; });
  std::vector<double> rank(pooled.size());
  tie_term = 0.0;
  for (size_t i = 0; i < order.size();) {
    size_t j = i;
    while (j + 1 < order.size() && pooled[order[j + 1]] == pooled[order[i]]) ++j;
    const double mid = 0.5 * double(i + j) + 1.0;
    for (size_t k = i; k <= j; ++k) rank[order[k]] = mid;
    const double t = double(j - i + 1);
    tie_term += t * t * t - t;
    i = j + 1;
  }
  return rank;
}

/// Two-sided p from the normal approximation: mean mn/2, variance mn/12 ((N+1) - ties/(N(N-1))), with a
/// continuity correction of 1/2.
double normal_p(double u, size_t m, size_t n, double tie_term) {
  const double mn = double(m) * double(n), total = double(m + n);
  const double variance = mn / 12.0 * ((total + 1.0) - tie_term / (total * (total - 1.0)));
  if (!(variance > 0.0)) return 1.0;  // every value equal
  const double z = (std::fabs(u - mn / 2.0) - 0.5) / std::sqrt(variance);
  return std::min(1.0, std::erfc(std::max(z, 0.0) / std::sqrt(2.0)));
}

}  // namespace

// The number of arrangements with U = k follows f(m, n, k) = f(m - 1, n, k - n) + f(m, n - 1, k) (Mann and
// Whitney 1947); divided by C(m + n, m) it is the null distribution.
double mann_whitney_exact_cdf(size_t m, size_t n, double u) {
  const size_t max_u = m * n;
  // counts[j][k]: arrangements of i x-values and j y-values with U = k, built up over i.
  std::vector<std::vector<double>> counts(n + 1, std::vector<double>(max_u + 1, 0.0));
  for (size_t j = 0; j <= n; ++j) counts[j][0] = 1.0;  // i = 0: U = 0
  for (size_t i = 1; i <= m; ++i) {
    std::vector<std::vector<double>> next(n + 1, std::vector<double>(max_u + 1, 0.0));
    next[0][0] = 1.0;
    for (size_t j = 1; j <= n; ++j)
      for (size_t k = 0; k <= i * j; ++k) next[j][k] = (k >= j ? counts[j][k - j] : 0.0) + next[j - 1][k];
    counts.swap(next);
  }
  double below = 0.0, all = 0.0;
  for (size_t k = 0; k <= max_u; ++k) {
    all += counts[n][k];
    if (double(k) <= u + 1e-9) below += counts[n][k];
  }
  return below / all;
}

MannWhitney mann_whitney_u(std::span<const double> x, std::span<const double> y) {
  MannWhitney r;
  const size_t m = x.size(), n = y.size();
  if (m == 0 || n == 0) return r;
  std::vector<double> pooled(x.begin(), x.end());
  pooled.insert(pooled.end(), y.begin(), y.end());
  double tie_term = 0.0;
  const std::vector<double> rank = mid_ranks(pooled, tie_term);
  double rank_sum = 0.0;
  for (size_t i = 0; i < m; ++i) rank_sum += rank[i];
  r.u = rank_sum - double(m) * double(m + 1) / 2.0;
  r.exact = tie_term == 0.0 && m <= kMannWhitneyExactMax && n <= kMannWhitneyExactMax;
  if (r.exact) {
    const double tail = std::min(r.u, double(m) * double(n) - r.u);  // the distribution is symmetric
    r.p_value = std::min(1.0, 2.0 * mann_whitney_exact_cdf(m, n, tail));
  } else {
    r.p_value = normal_p(r.u, m, n, tie_term);
  }
  return r;
}

}  // namespace ab
