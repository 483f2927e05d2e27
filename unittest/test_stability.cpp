// stability stress tests of fix pe_jump and fix pe_jump/async (the quick part
// of bench/stability): the largest stable time step, measured by bisection,
// against the linear stability limit h_c = 2 / omega_max computed here
// independently (closed form, Sturm sequences, Bloch modes), for chains of
// several sizes, mixed stiffnesses and masses, a 2d lattice, and the fine
// step of fix pe_jump/async; and a clean stop with the instability error 5%
// above the limit while 5% below runs with bounded jumps

#include "pe_jump_systems.h"

#include "exceptions.h"

#include "gmock/gmock.h"
#include "gtest/gtest.h"

#include <algorithm>
#include <cmath>
#include <functional>
#include <string>
#include <vector>

using namespace PEJumpTest;
using ::testing::ContainsRegex;

namespace {

// deterministic pseudo-random numbers in [-0.5, 0.5)
struct Lcg {
  unsigned state;
  double operator()()
  {
    state = 1664525u * state + 1013904223u;
    return (state >> 8) / double(1u << 24) - 0.5;
  }
};

std::string num(double x)
{
  return fmt::format("{:.17g}", x);
}

// chain along x with fixed ends: atom 1 and atom n+2 are walls (not
// integrated), atoms 2..n+1 are group "chain" with masses mass[i]; bond i
// (i = 0..n) joins atoms i+1 and i+2 with E = kb[i]/2 (r - 1)^2, i.e.
// stiffness kb[i]. Random displacements and velocities of size amp along x.
// Atoms 2..nfast+1 form group "fast".
void fixed_chain(Sim &s, const std::vector<double> &kb, const std::vector<double> &mass,
                 unsigned seed, int nfast = 0, double amp = 1e-3)
{
  const int n = (int) mass.size();
  const int nb = n + 1;
  s.cmds({"units lj", "atom_style bond", "atom_modify map array", "boundary f f f",
          "region box block -2 " + std::to_string(n + 3) + " -2 2 -2 2",
          fmt::format("create_box {} box bond/types {} extra/bond/per/atom 2", n + 1, nb),
          "mass 1 1.0"});
  for (int i = 0; i < n; ++i) s.cmd(fmt::format("mass {} {}", i + 2, num(mass[i])));
  s.cmd("create_atoms 1 single 0 0 0");
  for (int i = 1; i <= n; ++i) s.cmd(fmt::format("create_atoms {} single {} 0 0", i + 1, i));
  s.cmd(fmt::format("create_atoms 1 single {} 0 0", n + 1));
  Lcg rnd{seed};
  for (int i = 1; i <= n; ++i) {
    const int j = s.lmp->atom->map(i + 1);
    s.lmp->atom->x[j][0] += amp * rnd();
    s.lmp->atom->v[j][0] = amp * rnd();
  }
  s.cmd("bond_style harmonic");
  for (int b = 0; b < nb; ++b) {
    s.cmd(fmt::format("bond_coeff {} {} 1.0", b + 1, num(0.5 * kb[b])));
    s.cmd(fmt::format("create_bonds single/bond {} {} {}", b + 1, b + 1, b + 2));
  }
  s.cmds({"pair_style zero 1.0", "pair_coeff * *", "comm_modify cutoff 3.0",
          "group chain id 2:" + std::to_string(n + 1)});
  if (nfast > 0) s.cmd("group fast id 2:" + std::to_string(nfast + 1));
}

// number of eigenvalues below x of the symmetric tridiagonal matrix with
// diagonal d and off-diagonal e (Sturm sequence of the LDL^T pivots)
int sturm_count(const std::vector<double> &d, const std::vector<double> &e, double x)
{
  int count = 0;
  double q = 1.0;
  for (size_t i = 0; i < d.size(); ++i) {
    const double off = (i > 0) ? e[i - 1] * e[i - 1] : 0.0;
    q = d[i] - x - ((i > 0) ? off / q : 0.0);
    if (q == 0.0) q = -1e-300;
    if (q < 0.0) ++count;
  }
  return count;
}

// largest eigenvalue of M^{-1/2} K M^{-1/2} for the chain of fixed_chain()
// (the first nrows atoms only, e.g. a fast block), by bisection on the
// Sturm count
double chain_lambda_max(const std::vector<double> &kb, const std::vector<double> &mass,
                        int nrows = -1)
{
  const int n = (nrows < 0) ? (int) mass.size() : nrows;
  std::vector<double> d(n), e(n > 0 ? n - 1 : 0);
  for (int i = 0; i < n; ++i) d[i] = (kb[i] + kb[i + 1]) / mass[i];
  for (int i = 0; i + 1 < n; ++i) e[i] = -kb[i + 1] / std::sqrt(mass[i] * mass[i + 1]);
  double lo = 0.0, hi = 0.0;
  for (int i = 0; i < n; ++i)
    hi = std::max(hi,
                  d[i] + ((i > 0) ? std::fabs(e[i - 1]) : 0.0) +
                      ((i + 1 < n) ? std::fabs(e[i]) : 0.0));    // Gershgorin
  for (int it = 0; it < 200; ++it) {
    const double mid = 0.5 * (lo + hi);
    if (sturm_count(d, e, mid) == n)
      hi = mid;
    else
      lo = mid;
  }
  return 0.5 * (lo + hi);
}

// outcome of one run: the error message ("" if none) and the jump energy
// relative to its value at the start (kick initialisation: [v]^0 = h F/m)
struct Outcome {
  std::string error;
  double jump_growth = 0.0;
  bool finite = true;
};

// build the system (including the fix, with ID 1, and the time step), run
// nsteps; the error of an unstable run is caught
Outcome run_case(const std::function<void(Sim &)> &build, int nsteps)
{
  Sim s;
  build(s);
  Outcome o;
  s.cmds({"thermo 0", "run 0 post no"});
  const double j0 = std::max(s.vec("1", 1), 1e-300);
  const std::string error = error_from([&] {
    s.cmd("run " + std::to_string(nsteps) + " post no");
    o.jump_growth = s.vec("1", 1) / j0;
  });
  if (error != "no error") o.error = error;
  for (int i = 0; i < s.lmp->atom->nlocal; ++i)
    for (int k = 0; k < 3; ++k)
      if (!std::isfinite(s.lmp->atom->x[i][k]) || !std::isfinite(s.lmp->atom->v[i][k]))
        o.finite = false;
  return o;
}

// largest stable step / hc by bisection in [lo, hi]: stable = the run ends
// without error and the jump energy has not grown more than 100-fold
double measured_limit(const std::function<void(Sim &, double)> &build, double hc, int nsteps,
                      double lo = 0.9, double hi = 1.12, int iterations = 12)
{
  for (int it = 0; it < iterations; ++it) {
    const double mid = 0.5 * (lo + hi);
    const Outcome o = run_case(
        [&](Sim &s) {
          build(s, mid * hc);
        },
        nsteps);
    if (o.error.empty() && o.jump_growth < 100.0)
      lo = mid;
    else
      hi = mid;
  }
  return 0.5 * (lo + hi);
}

// 5% above hc: the instability error, finite state; 5% below: runs, jumps bounded
void expect_clean_stop_above_and_run_below(const std::function<void(Sim &, double)> &build,
                                           double hc, int nsteps, const std::string &style)
{
  const Outcome above = run_case(
      [&](Sim &s) {
        build(s, 1.05 * hc);
      },
      nsteps);
  EXPECT_THAT(above.error, ContainsRegex("Fix " + style + " is unstable at step [0-9]+"));
  EXPECT_TRUE(above.finite);
  const Outcome below = run_case(
      [&](Sim &s) {
        build(s, 0.95 * hc);
      },
      nsteps);
  EXPECT_EQ(below.error, "");
  EXPECT_TRUE(below.finite);
  EXPECT_LT(below.jump_growth, 100.0);
}

}    // namespace

/* ----------------------------------------------------------------------
   uniform chains with fixed ends: lambda_k = 2 k (1 - cos(k pi / (n+1))) / m,
   h_c = 2 / sqrt(lambda_n); sizes 3, 10, 40, midpoint and lobatto 3
------------------------------------------------------------------------- */

TEST(Stability, UniformChainCflLimitMatchesClosedForm)
{
  const double k = 100.0;
  for (const int n : {3, 10, 40}) {
    const double lam = 2.0 * k * (1.0 + std::cos(M_PI / (n + 1)));
    const double hc = 2.0 / std::sqrt(lam);
    const std::vector<double> kb(n + 1, k), mass(n, 1.0);
    // the independent Sturm bisection agrees with the closed form
    EXPECT_NEAR(chain_lambda_max(kb, mass) / lam, 1.0, 1e-12);
    for (const std::string rule : {"midpoint", "lobatto 3"}) {
      auto build = [&](Sim &s, double h) {
        fixed_chain(s, kb, mass, 11u + n);
        s.cmds({"fix 1 chain pe_jump quadrature " + rule, "timestep " + num(h)});
      };
      const double ratio = measured_limit(build, hc, 5000);
      EXPECT_NEAR(ratio, 1.0, 0.002) << "n = " << n << ", " << rule;
      if (n == 10) expect_clean_stop_above_and_run_below(build, hc, 20000, "pe_jump");
    }
  }
}

/* ----------------------------------------------------------------------
   mixed stiffnesses (1 to 400) and masses (1 to 4): the limit is set by
   the largest eigenvalue of M^{-1/2} K M^{-1/2}, not by 2 sqrt(m_min/k_max)
------------------------------------------------------------------------- */

TEST(Stability, MixedChainCflLimitMatchesSturmBisection)
{
  const int n = 16;
  std::vector<double> kb(n + 1), mass(n);
  Lcg rnd{2024u};
  for (auto &x : kb) x = std::pow(400.0, rnd() + 0.5);
  for (auto &x : mass) x = std::pow(4.0, rnd() + 0.5);
  const double lam = chain_lambda_max(kb, mass);
  const double hc = 2.0 / std::sqrt(lam);
  // the naive bound with the smallest mass and stiffest spring is not the limit
  const double kmax = *std::max_element(kb.begin(), kb.end());
  const double mmin = *std::min_element(mass.begin(), mass.end());
  EXPECT_GT(std::fabs(hc / std::sqrt(mmin / kmax) - 1.0), 0.05);
  auto build = [&](Sim &s, double h) {
    fixed_chain(s, kb, mass, 5u);
    s.cmds({"fix 1 chain pe_jump quadrature lobatto 3", "timestep " + num(h)});
  };
  EXPECT_NEAR(measured_limit(build, hc, 5000), 1.0, 0.002);
  expect_clean_stop_above_and_run_below(build, hc, 20000, "pe_jump");
}

/* ----------------------------------------------------------------------
   periodic square lattice (6 x 6, spacing 1) with nearest-neighbour
   springs k1 and diagonal springs k2 in 2d: omega_max^2 is the largest
   eigenvalue of the 2x2 dynamical matrix over the 36 Bloch vectors
------------------------------------------------------------------------- */

TEST(Stability, SquareLatticeCflLimitMatchesBlochModes)
{
  const int L = 6;
  const double k1 = 100.0, k2 = 40.0;
  double lam = 0.0;
  for (int a = 0; a < L; ++a)
    for (int b = 0; b < L; ++b) {
      const double qx = 2.0 * M_PI * a / L, qy = 2.0 * M_PI * b / L;
      const double sp = k2 * (1.0 - std::cos(qx + qy)), sm = k2 * (1.0 - std::cos(qx - qy));
      const double dxx = 2.0 * k1 * (1.0 - std::cos(qx)) + sp + sm;
      const double dyy = 2.0 * k1 * (1.0 - std::cos(qy)) + sp + sm;
      const double dxy = sp - sm;
      const double top =
          0.5 * (dxx + dyy) + std::sqrt(0.25 * (dxx - dyy) * (dxx - dyy) + dxy * dxy);
      lam = std::max(lam, top);
    }
  const double hc = 2.0 / std::sqrt(lam);
  auto build = [&](Sim &s, double h) {
    s.cmds({"units lj", "dimension 2", "atom_style bond", "atom_modify map array", "boundary p p p",
            "lattice sq 1.0", fmt::format("region box block 0 {} 0 {} -0.5 0.5", L, L),
            "create_box 1 box bond/types 2 extra/bond/per/atom 8 extra/special/per/atom 40",
            "create_atoms 1 box", "mass 1 1.0", "pair_style zero 1.6", "pair_coeff * *",
            "special_bonds lj/coul 0.0 1.0 1.0", "bond_style harmonic",
            "bond_coeff 1 " + num(0.5 * k1) + " 1.0",
            "bond_coeff 2 " + num(0.5 * k2) + " " + num(std::sqrt(2.0)),
            "create_bonds many all all 1 0.99 1.01", "create_bonds many all all 2 1.40 1.42",
            "comm_modify cutoff 3.0"});
    Lcg rnd{99u};
    for (int i = 0; i < s.lmp->atom->nlocal; ++i)
      for (int d = 0; d < 2; ++d) {
        s.lmp->atom->x[i][d] += 1e-3 * rnd();
        s.lmp->atom->v[i][d] = 1e-3 * rnd();
      }
    s.cmds({"fix 1 all pe_jump", "timestep " + num(h)});
  };
  {
    Sim s;
    build(s, 0.01);
    ASSERT_EQ(s.lmp->atom->nbonds, 4 * L * L);
  }
  EXPECT_NEAR(measured_limit(build, hc, 5000), 1.0, 0.002);
  expect_clean_stop_above_and_run_below(build, hc, 20000, "pe_jump");
}

/* ----------------------------------------------------------------------
   fix pe_jump/async, K = 4: a stiff segment (fast group, k = 2500) and a
   soft one (k = 4); the fine step limit is that of the block of the
   fine-clock atoms (the fast atoms, the last one coupled to the soft part),
   2 / sqrt(lambda_max) of its rows of the stiffness matrix. The time step
   is the coarse step K h_F; runs of 5000 coarse steps (20000 fine)
------------------------------------------------------------------------- */

TEST(Stability, AsyncFineStepLimitMatchesFastBlock)
{
  const int nfast = 8, nslow = 8, K = 4;
  std::vector<double> kb(nfast + nslow + 1, 4.0), mass(nfast + nslow, 1.0);
  for (int i = 0; i <= nfast - 1; ++i) kb[i] = 2500.0;
  const double hc = 2.0 / std::sqrt(chain_lambda_max(kb, mass, nfast));
  // the slow atoms are far below their limit at h_S = K h_F
  const double hcs = 2.0 /
      std::sqrt(chain_lambda_max(std::vector<double>(kb.begin() + nfast, kb.end()),
                                 std::vector<double>(mass.begin() + nfast, mass.end())));
  ASSERT_LT(K * 1.12 * hc, 0.2 * hcs);
  auto build = [&](Sim &s, double h) {
    fixed_chain(s, kb, mass, 17u, nfast);
    s.cmds({fmt::format("fix 1 chain pe_jump/async {} fast", K), "timestep " + num(K * h)});
  };
  EXPECT_NEAR(measured_limit(build, hc, 5000), 1.0, 0.002);
  expect_clean_stop_above_and_run_below(build, hc, 5000, "pe_jump/async");
}
