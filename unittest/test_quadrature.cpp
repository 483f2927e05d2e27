// unit tests for the quadrature rules of fix pe_jump: symmetry, weights,
// and the degree of exactness of each rule (exact up to its degree, not
// beyond), checked on the monomials of [0,1] against exact integrals

#include "pe_jump_quadrature.h"

#include "gtest/gtest.h"

#include <cmath>

using LAMMPS_NS::PEJump::Quadrature;

namespace {

double integrate(const Quadrature &q, int power)
{
  double sum = 0.0;
  for (int k = 0; k < q.size(); ++k) sum += q.weight[k] * std::pow(q.node[k], power);
  return sum;
}

struct RuleCase {
  Quadrature::Family family;
  int npoints;
  int degree;
};

class QuadratureRule : public ::testing::TestWithParam<RuleCase> {};

}    // namespace

TEST_P(QuadratureRule, SymmetricNodesAndUnitWeight)
{
  const auto c = GetParam();
  Quadrature q(c.family, c.npoints);
  ASSERT_EQ(q.size(), c.npoints);
  double wsum = 0.0;
  for (int k = 0; k < q.size(); ++k) {
    wsum += q.weight[k];
    EXPECT_GT(q.weight[k], 0.0);
    EXPECT_GE(q.node[k], 0.0);
    EXPECT_LE(q.node[k], 1.0);
    if (k > 0) { EXPECT_LT(q.node[k - 1], q.node[k]); }
    EXPECT_NEAR(q.node[k], 1.0 - q.node[q.size() - 1 - k], 1.2e-16);
    EXPECT_DOUBLE_EQ(q.weight[k], q.weight[q.size() - 1 - k]);
  }
  EXPECT_NEAR(wsum, 1.0, 2e-16);
  if (c.family == Quadrature::LOBATTO) {
    EXPECT_EQ(q.node.front(), 0.0);
    EXPECT_EQ(q.node.back(), 1.0);
    EXPECT_EQ(q.primary(), q.size() - 1);
  } else {
    EXPECT_GT(q.node.front(), 0.0);
    EXPECT_LT(q.node.back(), 1.0);
    EXPECT_GE(q.node[q.primary()], 0.5);
  }
}

TEST_P(QuadratureRule, ExactUpToItsDegreeOnly)
{
  const auto c = GetParam();
  Quadrature q(c.family, c.npoints);
  EXPECT_EQ(q.degree(), c.degree);
  for (int p = 0; p <= c.degree; ++p)
    EXPECT_NEAR(integrate(q, p), 1.0 / (p + 1), 4e-16) << q.name() << " monomial degree " << p;
  // the first monomial beyond the degree is not integrated exactly
  const double miss = std::fabs(integrate(q, c.degree + 1) - 1.0 / (c.degree + 2));
  EXPECT_GT(miss, 1e-6) << q.name() << " exact beyond its degree";
}

INSTANTIATE_TEST_SUITE_P(
    Rules, QuadratureRule,
    ::testing::Values(RuleCase{Quadrature::LEGENDRE, 1, 1}, RuleCase{Quadrature::LEGENDRE, 2, 3},
                      RuleCase{Quadrature::LEGENDRE, 3, 5}, RuleCase{Quadrature::LEGENDRE, 4, 7},
                      RuleCase{Quadrature::LEGENDRE, 5, 9}, RuleCase{Quadrature::LOBATTO, 2, 1},
                      RuleCase{Quadrature::LOBATTO, 3, 3}, RuleCase{Quadrature::LOBATTO, 4, 5},
                      RuleCase{Quadrature::LOBATTO, 5, 7}));

TEST(Quadrature, KnownNodesToFullPrecision)
{
  // Gauss-Legendre 2: 1/2 -+ sqrt(3)/6; Lobatto 4 interior: 1/2 -+ sqrt(5)/10
  Quadrature g2(Quadrature::LEGENDRE, 2);
  EXPECT_NEAR(g2.node[0], 0.21132486540518711775, 1e-16);
  Quadrature l4(Quadrature::LOBATTO, 4);
  EXPECT_NEAR(l4.node[1], 0.27639320225002103036, 1e-16);
  EXPECT_NEAR(l4.weight[1], 5.0 / 12.0, 1e-16);
  Quadrature g5(Quadrature::LEGENDRE, 5);
  EXPECT_NEAR(g5.node[0], 0.046910077030668003601, 1e-16);
  EXPECT_NEAR(g5.weight[0], 0.11846344252809454376, 1e-16);
}

TEST(Quadrature, RejectsPointCountsOutOfRange)
{
  EXPECT_THROW(Quadrature(Quadrature::LEGENDRE, 0), std::invalid_argument);
  EXPECT_THROW(Quadrature(Quadrature::LEGENDRE, 6), std::invalid_argument);
  EXPECT_THROW(Quadrature(Quadrature::LOBATTO, 1), std::invalid_argument);
  EXPECT_THROW(Quadrature(Quadrature::LOBATTO, 6), std::invalid_argument);
}

// quadrature auto: each nested Lobatto rule (2, 3, 5 points) keeps the nodes
// of the rule before and names every node by its place in the finest rule;
// the nodes it adds are exactly those the rule before lacks, and each level
// integrates the monomials up to its own degree
TEST(Quadrature, NestedLobattoRulesShareTheirNodes)
{
  const LAMMPS_NS::PEJump::NestedLobatto nested;
  ASSERT_EQ(nested.levels(), 3);
  const Quadrature &finest = nested.finest();
  ASSERT_EQ(finest.size(), 5);
  int added_total = 0;
  for (int level = 0; level < nested.levels(); ++level) {
    const Quadrature &r = nested.rule(level);
    EXPECT_EQ(r.family(), Quadrature::LOBATTO);
    EXPECT_EQ(r.size(), (level == 0) ? 2 : (level == 1) ? 3 : 5);
    for (int j = 0; j < r.size(); ++j) {
      const int k = nested.finest_index(level, j);
      EXPECT_DOUBLE_EQ(finest.node[k], r.node[j]);
      bool before = false;
      if (level > 0) {
        const Quadrature &prev = nested.rule(level - 1);
        for (int i = 0; i < prev.size(); ++i) before |= (prev.node[i] == r.node[j]);
      }
      EXPECT_EQ(nested.added(level, j), !before) << level << " " << j;
      added_total += nested.added(level, j) ? 1 : 0;
    }
    for (int p = 0; p <= r.degree(); ++p)
      EXPECT_NEAR(integrate(r, p), 1.0 / (p + 1), 1e-15) << level << " " << p;
  }
  // every node of the finest rule is evaluated once over the three levels
  EXPECT_EQ(added_total, finest.size());
}

// the start of the quadrature sum: a Lobatto rule's start node is the last
// step's end node (an unset one, NaN, is the primary node's forces), a
// Legendre rule has none
TEST(Quadrature, StartSumReusesTheLastEndNode)
{
  const double nan = std::nan("");
  const Quadrature lobatto(Quadrature::LOBATTO, 3);
  ASSERT_TRUE(lobatto.reuses_start_node());
  EXPECT_EQ(lobatto.first_sampled(), 1);
  const auto begin = lobatto.start_sum();
  double fstart[3] = {nan, nan, nan}, sum[3];
  const double f1[3] = {6.0, -12.0, 0.5}, f2[3] = {3.0, 0.0, 1.0};
  begin(f1, fstart, sum);    // first step: start = end = f1
  for (int k = 0; k < 3; k++) EXPECT_DOUBLE_EQ(sum[k], (1.0 / 6.0 + 1.0 / 6.0) * f1[k]) << k;
  begin(f2, fstart, sum);    // next step: start f1, end f2
  for (int k = 0; k < 3; k++) {
    EXPECT_DOUBLE_EQ(sum[k], f1[k] / 6.0 + f2[k] / 6.0) << k;
    EXPECT_EQ(fstart[k], f2[k]) << k;
  }

  const Quadrature legendre(Quadrature::LEGENDRE, 1);
  EXPECT_FALSE(legendre.reuses_start_node());
  EXPECT_EQ(legendre.first_sampled(), 0);
  legendre.start_sum()(f1, nullptr, sum);
  for (int k = 0; k < 3; k++) EXPECT_EQ(sum[k], f1[k]) << k;
}

/* ----------------------------------------------------------------------
   the properties the fixes ask a rule for follow from its nodes: end
   nodes (both ends of the step are nodes), the primary node (the step
   end if it is a node, else the middle), whether an impulse at the
   primary node needs the centre as an extra node; the names of the input
------------------------------------------------------------------------- */

TEST(Quadrature, PropertiesFollowFromTheNodes)
{
  for (int n = 1; n <= Quadrature::MAX_POINTS; n++) {
    const Quadrature legendre(Quadrature::LEGENDRE, n);
    EXPECT_FALSE(legendre.has_end_nodes());
    EXPECT_FALSE(legendre.only_end_nodes());
    EXPECT_EQ(legendre.primary(), n / 2);
    EXPECT_EQ(legendre.primary_off_centre(), n % 2 == 0) << n;
    if (n % 2 == 0) {
      const Quadrature centred(Quadrature::LEGENDRE, n, true);
      EXPECT_EQ(centred.size(), n + 1);
      EXPECT_EQ(centred.node[centred.primary()], 0.5);
      EXPECT_EQ(centred.weight[centred.primary()], 0.0);
    }
  }
  for (int n = 2; n <= Quadrature::MAX_POINTS; n++) {
    const Quadrature lobatto(Quadrature::LOBATTO, n);
    EXPECT_TRUE(lobatto.has_end_nodes());
    EXPECT_TRUE(lobatto.reuses_start_node());
    EXPECT_EQ(lobatto.only_end_nodes(), n == 2);
    EXPECT_EQ(lobatto.node[lobatto.primary()], 1.0);
    EXPECT_FALSE(lobatto.primary_off_centre());
  }
  Quadrature::Family family = Quadrature::LEGENDRE;
  EXPECT_TRUE(Quadrature::family_named("lobatto", family));
  EXPECT_EQ(family, Quadrature::LOBATTO);
  EXPECT_EQ(Quadrature::min_points(family), 2);
  EXPECT_TRUE(Quadrature::family_named("legendre", family));
  EXPECT_EQ(family, Quadrature::LEGENDRE);
  EXPECT_EQ(Quadrature::min_points(family), 1);
  EXPECT_FALSE(Quadrature::family_named("radau", family));
}
