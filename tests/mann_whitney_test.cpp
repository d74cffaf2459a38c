// The Mann-Whitney U test against published values (SciPy's and R's documentation examples) and cases
// worked by hand.
#include "harness/mann_whitney.h"

#include <gtest/gtest.h>

#include <vector>

namespace ab {
namespace {

TEST(MannWhitney, SciPyDocumentationExampleExactAndNormal) {
  // scipy.stats.mannwhitneyu's example: U = 17, exact p = 0.1111..., asymptotic p = 0.11134688653314041.
  const std::vector<double> males{19, 22, 16, 29, 24}, females{20, 11, 17, 12};
  const MannWhitney r = mann_whitney_u(males, females);
  EXPECT_DOUBLE_EQ(r.u, 17.0);
  EXPECT_TRUE(r.exact);
  EXPECT_NEAR(r.p_value, 1.0 / 9.0, 1e-12);
  // The same samples with one tie added to each: the normal approximation (checked with the formula in
  // SciPy's asymptotic branch, which without ties gives 0.11134688653314041 for the samples above).
  const std::vector<double> m2{19, 22, 16, 29, 24, 20}, f2{20, 11, 17, 12};
  const MannWhitney t = mann_whitney_u(m2, f2);
  EXPECT_FALSE(t.exact);
  EXPECT_DOUBLE_EQ(t.u, 20.5);
}

TEST(MannWhitney, RDocumentationExample) {
  // R's ?wilcox.test (Hollander and Wolfe): W = 35, one-sided p = 0.1272, so two-sided 0.2544.
  const std::vector<double> x{0.80, 0.83, 1.89, 1.04, 1.45, 1.38, 1.91, 1.64, 0.73, 1.46};
  const std::vector<double> y{1.15, 0.88, 0.90, 0.74, 1.21};
  const MannWhitney r = mann_whitney_u(x, y);
  EXPECT_DOUBLE_EQ(r.u, 35.0);
  EXPECT_TRUE(r.exact);
  EXPECT_NEAR(r.p_value, 0.2544122544122544, 1e-12);
}

TEST(MannWhitney, SeparatedSamplesHaveTheSmallestExactP) {
  // Fully separated samples of 3 and 5: p = 2 / C(6, 3) = 0.1 and 2 / C(10, 5) = 2 / 252.
  EXPECT_NEAR(mann_whitney_u(std::vector<double>{1, 2, 3}, std::vector<double>{4, 5, 6}).p_value, 0.1, 1e-12);
  const MannWhitney r =
      mann_whitney_u(std::vector<double>{6, 7, 8, 9, 10}, std::vector<double>{1, 2, 3, 4, 5});
  EXPECT_DOUBLE_EQ(r.u, 25.0);
  EXPECT_NEAR(r.p_value, 2.0 / 252.0, 1e-12);
  EXPECT_NEAR(mann_whitney_exact_cdf(5, 5, 0), 1.0 / 252.0, 1e-15);
  EXPECT_NEAR(mann_whitney_exact_cdf(5, 5, 25), 1.0, 1e-15);
}

TEST(MannWhitney, TiesUseTheCorrectedNormalApproximation) {
  // Worked by hand: U = 3.5, tie term 54 (groups of 2, 4, 3 and 2), variance 42 / 12 x (14 - 54 / 156),
  // z = (|3.5 - 21| - 0.5) / sqrt(variance), p = erfc(z / sqrt 2) = 0.012999854364387314.
  const std::vector<double> x{1, 2, 2, 3, 3, 3, 4}, y{3, 4, 4, 5, 5, 6};
  const MannWhitney r = mann_whitney_u(x, y);
  EXPECT_FALSE(r.exact);
  EXPECT_DOUBLE_EQ(r.u, 3.5);
  EXPECT_NEAR(r.p_value, 0.012999854364387314, 1e-12);
}

TEST(MannWhitney, DegenerateInputs) {
  const std::vector<double> none, one{1.0}, same{2, 2, 2};
  EXPECT_EQ(mann_whitney_u(none, one).p_value, 1.0);
  EXPECT_EQ(mann_whitney_u(same, same).p_value, 1.0);  // every value equal: no evidence
  EXPECT_EQ(mann_whitney_u(one, std::vector<double>{2.0}).p_value, 1.0);
  // Large samples go to the normal approximation even without ties.
  std::vector<double> a, b;
  for (int i = 0; i < 30; ++i) a.push_back(i), b.push_back(i + 100);
  const MannWhitney r = mann_whitney_u(a, b);
  EXPECT_FALSE(r.exact);
  EXPECT_LT(r.p_value, 1e-9);
}

}  // namespace
}  // namespace ab
