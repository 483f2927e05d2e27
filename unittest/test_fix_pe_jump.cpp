// physics and interface tests of fix pe_jump through the LAMMPS C++ API:
// every test asserts numbers (conservation to round-off, order, agreement
// with an independent implementation, evaluation counts, error messages)

#include "pe_jump_systems.h"

#include "atom_vec.h"

#include "domain.h"
#include "exceptions.h"
#include "fix.h"
#include "force.h"
#include "neighbor.h"
#include "pair_lj_cut.h"
#include "timer.h"
#include "update.h"

#include "gmock/gmock.h"
#include "gtest/gtest.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <fstream>
#include <functional>
#include <map>
#include <random>
#include <regex>
#include <sstream>

using namespace PEJumpTest;
using ::testing::ContainsRegex;
using ::testing::Not;

namespace {
// LAMMPS' peri example, shortened: a sphere moving down at speed indents a
// cylinder at rest (SI units); the kinetic energy after the run
double peri_indentation(const std::string &pair, const std::string &coeff, const std::string &fix,
                        double speed, double dt, int steps)
{
  Sim s;
  s.cmds({"units si",
          "boundary s s s",
          "atom_style peri",
          "atom_modify map array",
          "neighbor 0.0010 bin",
          "lattice sc 0.0005",
          "region target cylinder y 0.0 0.0 0.0030 -0.0030 0.0 units box",
          "create_box 1 target",
          "create_atoms 1 region target",
          "pair_style " + pair,
          "pair_coeff * * " + coeff,
          "set group all density 2200",
          "set group all volume 1.25e-10",
          "velocity all set 0.0 0.0 0.0 sum no units box",
          "fix 1 all " + fix,
          fmt::format("variable y equal 0.00155-{}*time", speed),
          "fix 2 all indent 1e17 sphere 0.0 v_y 0.0 0.0015 units box",
          fmt::format("timestep {}", dt),
          "thermo 0",
          fmt::format("run {} post no", steps)});
  return s.eval("ke");
}

constexpr double OMEGA = 50.0;

// pseudo-energy H~ = pe + f_ID and discrete energy H = pe + ke after a run
double pseudo_energy(Sim &s)
{
  return s.eval("c_thermo_pe+f_1");
}

// max - min of the values stored by a fix vector
double vector_range(Sim &s, const std::string &id)
{
  auto *vec = s.lmp->modify->get_fix_by_id(id);
  double lo = 1e300, hi = -1e300;
  for (int i = 0; i < vec->size_vector; ++i) {
    lo = std::min(lo, vec->compute_vector(i));
    hi = std::max(hi, vec->compute_vector(i));
  }
  return hi - lo;
}
double discrete_energy(Sim &s)
{
  if (!s.lmp->modify->get_compute_by_id("ke")) s.cmd("compute ke all ke");
  return s.eval("c_thermo_pe+c_ke");
}

void fpu_gni(Sim &s)
{
  double q[6], p[6];
  fpu_gni_values(OMEGA, q, p);
  fpu_chain(s, OMEGA, q, p);
}

// run n single steps with step sizes from next_dt(), return max |H~ - H~0|
// and record the deviations
double single_steps(Sim &s, int n, const std::function<double()> &next_dt,
                    std::vector<double> *dev = nullptr)
{
  s.cmd("thermo 1");
  s.cmd("run 0 post no");
  const double h0 = pseudo_energy(s);
  double worst = 0.0;
  for (int i = 0; i < n; ++i) {
    s.cmd("timestep " + fmt::format("{:.17g}", next_dt()));
    s.cmd("run 1 pre no post no");
    const double d = pseudo_energy(s) - h0;
    worst = std::max(worst, std::fabs(d));
    if (dev) dev->push_back(d);
  }
  return worst / std::fabs(h0);
}

// independent implementation of the scheme for the FPU chain (plain C++):
// midpoint or 3-point Lobatto quadrature of the exact forces, init kick
struct FpuReference {
  double q[8] = {0}, vh[8] = {0}, jump[8] = {0};

  static void force(const double *x, double *f)
  {
    for (int i = 0; i < 8; ++i) f[i] = 0.0;
    for (int i = 0; i < 7; ++i) {
      const double d = x[i + 1] - x[i];
      const double fb = (i % 2) ? 0.5 * OMEGA * OMEGA * d : 4.0 * d * d * d;
      f[i] += fb;
      f[i + 1] -= fb;
    }
    f[0] = f[7] = 0.0;    // walls
  }

  void start(const double *q0, const double *p0, double h)
  {
    for (int i = 0; i < 6; ++i) {
      q[i + 1] = q0[i];
      vh[i + 1] = p0[i];
    }
    double f[8];
    force(q, f);
    for (int i = 0; i < 8; ++i) {
      jump[i] = h * f[i];
      vh[i] += 0.5 * jump[i];
    }
  }

  void step(double h, bool lobatto3)
  {
    std::vector<std::pair<double, double>> rule;
    if (lobatto3)
      rule = {{0.0, 1.0 / 6.0}, {0.5, 2.0 / 3.0}, {1.0, 1.0 / 6.0}};
    else
      rule = {{0.5, 1.0}};
    double sum[8] = {0}, xn[8], f[8];
    for (auto &node : rule) {
      for (int i = 0; i < 8; ++i) xn[i] = q[i] + node.first * h * vh[i];
      force(xn, f);
      for (int i = 0; i < 8; ++i) sum[i] += node.second * f[i];
    }
    for (int i = 1; i < 7; ++i) {
      q[i] += h * vh[i];
      const double nj = 2.0 * h * sum[i] - jump[i];
      vh[i] += nj;
      jump[i] = nj;
    }
  }
};

}    // namespace

/* ----------------------------------------------------------------------
   agreement with an independent implementation
------------------------------------------------------------------------- */

TEST(PEJump, MatchesIndependentImplementationOnFpuChain)
{
  for (bool lobatto : {false, true}) {
    double q0[6], p0[6];
    fpu_gni_values(OMEGA, q0, p0);
    Sim s;
    fpu_chain(s, OMEGA, q0, p0);
    s.cmd(std::string("fix 1 chain pe_jump") + (lobatto ? " quadrature lobatto 3" : ""));
    s.cmd("timestep 0.001");
    s.cmd("thermo 500");
    s.cmd("run 2000");

    FpuReference ref;
    ref.start(q0, p0, 0.001);
    for (int n = 0; n < 2000; ++n) ref.step(0.001, lobatto);
    for (int i = 1; i <= 6; ++i) {
      EXPECT_NEAR(s.x(i + 1, 0) - i * FPU_SPACING, ref.q[i], 2e-12) << "lobatto " << lobatto;
      EXPECT_NEAR(s.v(i + 1, 0), ref.vh[i] - 0.5 * ref.jump[i], 2e-10) << "lobatto " << lobatto;
    }
  }
}

/* ----------------------------------------------------------------------
   pseudo-energy conservation for exact quadrature, any step sequence
------------------------------------------------------------------------- */

TEST(PEJump, PseudoEnergyConservedHarmonicMidpoint)
{
  Sim s;
  harmonic_ring(s, 10, 50.0, 1.0, 7);
  s.cmd("fix 1 all pe_jump");
  s.cmd("timestep 0.02");
  s.cmd("thermo 100");
  s.cmd("compute ke all ke");
  s.cmd("run 0 post no");
  const double e0 = discrete_energy(s);
  const double h0 = pseudo_energy(s);
  s.cmd("run 10000 post no");
  std::cout << "harmonic ring, midpoint, 1e4 steps: |dH~|/|H~| = "
            << std::fabs(pseudo_energy(s) - h0) / std::fabs(h0) << "\n";
  // coordinates of order 10: round-off of the energy is ~1e-14 relative
  EXPECT_LT(std::fabs(pseudo_energy(s) - h0) / std::fabs(h0), 1e-12);
  // the discrete energy is not conserved exactly, but stays close
  EXPECT_GT(std::fabs(discrete_energy(s) - e0), 1e-8);
  EXPECT_LT(std::fabs(discrete_energy(s) - e0) / e0, 0.05);
}

TEST(PEJump, PseudoEnergyConservedRandomStepsHarmonicMidpoint)
{
  Sim s;
  harmonic_ring(s, 10, 50.0, 1.0, 11);
  s.cmd("fix 1 all pe_jump");
  // +-10% around 0.01 (h omega_max = 0.2). Larger random changes pump the
  // parasitic mode until the discrete energy blows up within 10^4 steps
  // (doc/theory.md, section 3); the pseudo-energy stays constant all the same
  std::mt19937 gen(2024);
  std::uniform_real_distribution<double> dt(0.009, 0.011);
  std::vector<double> dev;
  const double worst = single_steps(
      s, 10000,
      [&] {
        return dt(gen);
      },
      &dev);
  std::cout << "harmonic ring, midpoint, 1e4 random steps: max |dH~|/|H~| = " << worst << "\n";
  EXPECT_LT(worst, 1e-12);
  // no drift: the deviation wanders like round-off, the mean over the last
  // thousand steps stays at round-off level instead of growing with time
  double tail = 0.0;
  for (size_t i = dev.size() - 1000; i < dev.size(); ++i) tail += dev[i];
  EXPECT_LT(std::fabs(tail / 1000.0) / std::fabs(pseudo_energy(s)), 1e-12);
}

TEST(PEJump, PseudoEnergyConservedFpuLobatto3)
{
  Sim s;
  fpu_gni(s);
  s.cmd("fix 1 chain pe_jump quadrature lobatto 3");
  s.cmd("timestep 0.001");
  s.cmd("thermo 1000");
  s.cmd("run 0 post no");
  const double h0 = pseudo_energy(s);
  s.cmd("run 10000 post no");
  std::cout << "FPU, lobatto 3, 1e4 steps: |dH~|/|H~| = "
            << std::fabs(pseudo_energy(s) - h0) / std::fabs(h0) << "\n";
  EXPECT_LT(std::fabs(pseudo_energy(s) - h0) / std::fabs(h0), 1e-12);
}

TEST(PEJump, PseudoEnergyConservedRandomStepsFpuLobatto3)
{
  Sim s;
  fpu_gni(s);
  s.cmd("fix 1 chain pe_jump quadrature lobatto 3");
  std::mt19937 gen(99);
  std::uniform_real_distribution<double> dt(0.0005, 0.0015);
  const double worst = single_steps(s, 10000, [&] {
    return dt(gen);
  });
  std::cout << "FPU, lobatto 3, 1e4 random steps: max |dH~|/|H~| = " << worst << "\n";
  EXPECT_LT(worst, 1e-12);
}

TEST(PEJump, MidpointNotExactOnQuarticSprings)
{
  // the midpoint rule is not exact for the quartic FPU springs: the
  // pseudo-energy then varies at the 1e-6 level (examples/fpu: 1.57e-6)
  Sim s;
  fpu_gni(s);
  s.cmd("fix 1 chain pe_jump");
  s.cmd("timestep 0.001");
  s.cmd("variable pt equal c_thermo_pe+f_1");
  s.cmd("fix pt all vector 10 v_pt");
  s.cmd("thermo 1000");
  s.cmd("run 20000 post no");
  const double range = vector_range(s, "pt");
  EXPECT_GT(range, 1e-8);
  EXPECT_LT(range, 1e-5);
}

/* ----------------------------------------------------------------------
   the discrete energy with init kick and init paper (doc/theory.md, section 4)
------------------------------------------------------------------------- */

TEST(PEJump, KickInitialisationKeepsParasiticModeOut)
{
  auto energy_range = [](const std::string &fix) {
    Sim s;
    fpu_gni(s);
    s.cmd(fix);
    s.cmd("timestep 0.001");
    s.cmd("compute ke all ke");
    s.cmd("variable H equal c_thermo_pe+c_ke");
    s.cmd("fix H all vector 10 v_H");
    s.cmd("thermo 10000");
    s.cmd("run 50000 post no");
    return vector_range(s, "H");
  };
  const double verlet = energy_range("fix 1 chain nve");
  const double kick = energy_range("fix 1 chain pe_jump");
  const double paper = energy_range("fix 1 chain pe_jump init paper");
  EXPECT_LT(kick, 1.1 * verlet);
  EXPECT_GT(paper, 2.0 * kick);
}

/* ----------------------------------------------------------------------
   second order: final positions of the FPU chain against a fine reference
------------------------------------------------------------------------- */

TEST(PEJump, SecondOrderConvergence)
{
  for (const std::string rule : {"midpoint", "lobatto 3", "legendre 2"}) {
    auto final_q = [&](double h, int nsteps) {
      Sim s;
      fpu_gni(s);
      s.cmd("fix 1 chain pe_jump quadrature " + rule);
      s.cmd("timestep " + fmt::format("{:.17g}", h));
      s.cmd("thermo 0");
      s.cmd("run " + std::to_string(nsteps) + " post no");
      std::vector<double> q;
      for (int i = 2; i <= 7; ++i) q.push_back(s.x(i, 0));
      return q;
    };
    const double T = 0.5;
    const auto ref = final_q(T / 32000, 32000);
    std::vector<double> err;
    for (int n : {500, 1000, 2000}) {
      const auto q = final_q(T / n, n);
      double e = 0.0;
      for (size_t i = 0; i < q.size(); ++i) e = std::max(e, std::fabs(q[i] - ref[i]));
      err.push_back(e);
    }
    const double order1 = std::log2(err[0] / err[1]);
    const double order2 = std::log2(err[1] / err[2]);
    std::cout << rule << ": measured orders " << order1 << " " << order2 << "\n";
    EXPECT_NEAR(order1, 2.0, 0.1) << rule;
    EXPECT_NEAR(order2, 2.0, 0.1) << rule;
  }
}

/* ----------------------------------------------------------------------
   momentum, reversibility
------------------------------------------------------------------------- */

TEST(PEJump, TotalMomentumConserved)
{
  Sim s;
  lj_liquid(s, 4, "mom no");
  s.cmd("fix 1 all pe_jump quadrature lobatto 3");
  s.cmd("timestep 0.005");
  s.cmd("variable px equal vcm(all,x)*mass(all)");
  s.cmd("variable py equal vcm(all,y)*mass(all)");
  s.cmd("variable pz equal vcm(all,z)*mass(all)");
  s.cmd("thermo 100");
  s.cmd("run 0 post no");
  const double p0[3] = {s.eval("v_px"), s.eval("v_py"), s.eval("v_pz")};
  ASSERT_GT(std::fabs(p0[0]) + std::fabs(p0[1]) + std::fabs(p0[2]), 1.0);
  s.cmd("run 1000 post no");
  std::cout << "LJ, lobatto 3, 1000 steps: |P - P0|_1 = "
            << std::fabs(s.eval("v_px") - p0[0]) + std::fabs(s.eval("v_py") - p0[1]) +
          std::fabs(s.eval("v_pz") - p0[2])
            << "\n";
  // momentum of 256 atoms with |v| ~ 2: round-off ~ 256 * 2 * 1e-16
  EXPECT_NEAR(s.eval("v_px"), p0[0], 1e-11);
  EXPECT_NEAR(s.eval("v_py"), p0[1], 1e-11);
  EXPECT_NEAR(s.eval("v_pz"), p0[2], 1e-11);
}

TEST(PEJump, TimeReversible)
{
  for (const std::string rule : {"midpoint", "lobatto 3"}) {
    Sim s;
    fpu_gni(s);
    s.cmd("fix 1 chain pe_jump quadrature " + rule);
    s.cmd("timestep 0.001");
    s.cmd("thermo 0");
    std::vector<double> x0, v0;
    for (int i = 2; i <= 7; ++i) {
      x0.push_back(s.x(i, 0));
      v0.push_back(s.v(i, 0));
    }
    s.cmd("run 3000 post no");
    for (int i = 0; i < s.lmp->atom->nlocal; ++i)
      for (int k = 0; k < 3; ++k) s.lmp->atom->v[i][k] = -s.lmp->atom->v[i][k];
    s.cmd("run 3000 post no");
    for (int i = 2; i <= 7; ++i) {
      EXPECT_NEAR(s.x(i, 0), x0[i - 2], 1e-11) << rule;
      EXPECT_NEAR(s.v(i, 0), -v0[i - 2], 1e-9) << rule;
    }
  }
}

/* ----------------------------------------------------------------------
   stability: CFL limit 2 sqrt(m/lambda); periodic chain of springs
   k = 2K = 100, m = 1: lambda = 4k/m = 400, limit h = 0.1
------------------------------------------------------------------------- */

TEST(PEJump, StableJustBelowCflLimit)
{
  Sim s;
  harmonic_ring(s, 10, 50.0, 0.5, 3);
  s.cmd("fix 1 all pe_jump");
  s.cmd("timestep 0.098");
  s.cmd("thermo 1000");
  s.cmd("run 0 post no");
  const double h0 = pseudo_energy(s);
  const double j0 = s.vec("1", 1);
  s.cmd("run 20000 post no");
  EXPECT_LT(std::fabs(pseudo_energy(s) - h0) / std::fabs(h0), 1e-11);
  EXPECT_LT(s.vec("1", 1), 1000.0 * std::max(j0, 1e-3 * std::fabs(h0)));
}

TEST(PEJump, InstabilityDetectedJustAboveCflLimit)
{
  Sim s(MPI_COMM_WORLD, false);
  harmonic_ring(s, 10, 50.0, 0.5, 3);
  s.cmd("fix 1 all pe_jump");
  s.cmd("timestep 0.102");
  s.cmd("thermo 1000");
  ::testing::internal::CaptureStdout();
  const std::string msg = error_in(s, "run 20000 post no");
  const std::string out = ::testing::internal::GetCapturedStdout();
  EXPECT_THAT(msg, ContainsRegex("Fix pe_jump is unstable at step [0-9]+"));
  // the log names the atom with the largest jump (one of the ring's 10)
  EXPECT_THAT(out, ContainsRegex("the largest jump at step [0-9]+: atom ([1-9]|10) at \\("));
  EXPECT_THAT(msg, ContainsRegex("beyond the stability limit"));
  // no other fix changed velocities: no advice about them
  EXPECT_THAT(msg, Not(ContainsRegex("reversed")));
  // stopped before anything became non-finite
  for (int i = 0; i < s.lmp->atom->nlocal; ++i)
    for (int k = 0; k < 3; ++k) {
      EXPECT_TRUE(std::isfinite(s.lmp->atom->x[i][k]));
      EXPECT_TRUE(std::isfinite(s.lmp->atom->v[i][k]));
    }
}

// a run that starts at rest and is loaded later: the jumps grow with the
// forces by any factor, which is no instability while they carry a
// negligible share of the kinetic energy. LAMMPS' peri example (an
// indenter into a peri/pmb cylinder, h = 1.25e-8) stopped at step 1172 as
// "unstable" with lobatto 2 (velocity Verlet, as fix nve, which ran on):
// the jumps had grown 1.05e6-fold from the first contact. It runs now and
// follows fix nve; a ring loaded from rest beyond the stability limit is
// still stopped
TEST(PEJump, LoadFromRestIsNoInstability)
{
  const auto indentation = [](const std::string &fix) {
    return peri_indentation("peri/pmb", "1.6863e22 0.0015001 0.0005 0.25", fix, 200.0, 1.25e-8,
                            1300);
  };
  const double nve = indentation("nve");
  EXPECT_NEAR(indentation("pe_jump quadrature lobatto 2"), nve, 1e-9 * nve);

  Sim s;
  harmonic_ring(s, 10, 50.0, 0.0, 3);
  s.cmds({"fix 1 all pe_jump", "variable push equal (time>1.0)*0.1", "group one id 1",
          "fix 2 one addforce v_push 0.0 0.0", "timestep 0.102", "thermo 0"});
  EXPECT_THAT(error_from([&]() {
                s.cmd("run 20000 post no");
              }),
              ContainsRegex("Fix pe_jump is unstable at step [0-9]+"));
}

// a hard collision that one step samples at its peak sends a jump of
// several times the atoms' speed through the two-step scheme for a step or
// two: no instability, though the jump moves an atom by half the skin in
// that step. Two LJ atoms meeting head on at speed 4 with h = 0.025 (a
// collision that fix nve takes with an energy error of 550 %): the guard
// stopped the run at step 13 (jumps 2.05-fold); it runs now, and H~
// ends 12 % below its start. At h = 0.03 the large jump stays (no damping
// without a thermostat): still stopped, once it has lasted
std::string head_on_collision(double dt, double *pseudo_change)
{
  Sim s;
  s.cmds({"units lj",
          "atom_style atomic",
          "boundary p p p",
          "region box block -6 6 -6 6 -6 6",
          "create_box 1 box",
          "create_atoms 1 single -1.5 0.05 0",
          "create_atoms 1 single 1.5 0 0",
          "mass 1 1.0",
          "pair_style lj/cut 2.5",
          "pair_coeff 1 1 1.0 1.0",
          "neighbor 0.3 bin",
          "neigh_modify every 1 delay 0 check yes",
          "group a id 1",
          "group b id 2",
          "velocity a set 4.0 0 0",
          "velocity b set -4.0 0 0",
          "fix 1 all pe_jump",
          fmt::format("timestep {}", dt),
          "thermo 0",
          "run 0 post no"});
  const double h0 = pseudo_energy(s);
  const std::string error = error_from([&]() {
    s.cmd("run 100 post no");
  });
  if (pseudo_change) *pseudo_change = std::fabs(pseudo_energy(s) - h0) / h0;
  return error;
}

TEST(PEJump, CollisionSpikeIsNoInstability)
{
  double change = 0.0;
  EXPECT_EQ(head_on_collision(0.025, &change), "no error");
  EXPECT_LT(change, 0.15);
  EXPECT_THAT(head_on_collision(0.03, nullptr),
              ContainsRegex("Fix pe_jump is unstable at step [0-9]+"));
}

/* ----------------------------------------------------------------------
   split runs and restarts reproduce an unbroken run
------------------------------------------------------------------------- */

namespace {
// unwrapped positions and velocities by atom ID
std::vector<double> lj_state(Sim &s)
{
  std::vector<double> out;
  for (int id = 1; id <= s.lmp->atom->natoms; ++id) {
    const int i = s.lmp->atom->map(id);
    double unwrap[3];
    s.lmp->domain->unmap(s.lmp->atom->x[i], s.lmp->atom->image[i], unwrap);
    for (int k = 0; k < 3; ++k) {
      out.push_back(unwrap[k]);
      out.push_back(s.v(id, k));
    }
  }
  return out;
}
}    // namespace

/* ----------------------------------------------------------------------
   a single-node step that nothing looks at afterwards begins the next step
   in the same pass: the trajectory is the same, bit for bit, as with the
   steps kept apart (which an end-of-step fix forces; here one that never
   acts in the run), whatever the options
------------------------------------------------------------------------- */

TEST(PEJump, BeginningStepsAheadKeepsTheTrajectory)
{
  for (const std::string opts : {"", "damp 0.05", "quadrature legendre 3", "init paper"}) {
    std::vector<double> apart, ahead;
    for (const bool keep_apart : {true, false}) {
      Sim s;
      lj_liquid(s);
      s.cmds({"fix 1 all pe_jump " + opts, "timestep 0.005", "thermo 0"});
      if (keep_apart) s.cmd("fix 2 all ave/time 1000000 1 1000000 c_thermo_temp");
      s.cmd("run 150 post no");
      (keep_apart ? apart : ahead) = lj_state(s);
    }
    ASSERT_EQ(apart.size(), ahead.size());
    double d = 0.0;
    for (size_t i = 0; i < ahead.size(); ++i) d = std::max(d, std::fabs(ahead[i] - apart[i]));
    EXPECT_EQ(d, 0.0) << opts;
  }
}

namespace {
// stops the run from inside a step, as fix plumed or a library caller may
// (timer->force_timeout()); a pre_reverse hook, so that fix pe_jump takes
// it for neither a force nor a velocity change
class FixStopAt : public LAMMPS_NS::Fix {
 public:
  FixStopAt(LAMMPS_NS::LAMMPS *lmp, int narg, char **arg) :
      Fix(lmp, narg, arg), step(LAMMPS_NS::utils::bnumeric(FLERR, arg[3], false, lmp))
  {
  }
  int setmask() override { return LAMMPS_NS::FixConst::PRE_REVERSE; }
  void pre_reverse(int, int) override
  {
    if (update->ntimestep == step) timer->force_timeout();
  }
  LAMMPS_NS::bigint step;
};

LAMMPS_NS::Fix *stop_at_creator(LAMMPS_NS::LAMMPS *lmp, int narg, char **arg)
{
  return new FixStopAt(lmp, narg, arg);
}
}    // namespace

/* ----------------------------------------------------------------------
   damp auto damps beside a thermostat, over 1000 steps: first order in the
   time step, which shows in econserve (LJ liquid with temp/berendsen:
   drift 1.07, 0.38, 0.15 as h halves; damp 0: 0.63, 0.16, 0.04). The log
   says when it starts, once; nothing where it does not damp
------------------------------------------------------------------------- */

TEST(PEJump, DampAutoSaysWhenItDamps)
{
  // what the log says about damp auto over one run (or two): "" if nothing
  const auto told = [](const std::string &rule, const std::string &other, int runs) {
    Sim s(MPI_COMM_WORLD, false);
    lj_liquid(s, 3);
    s.cmds({"fix int all pe_jump quadrature " + rule, "fix other all " + other, "thermo 0"});
    ::testing::internal::CaptureStdout();
    for (int run = 0; run < runs; ++run) s.cmd("run 30 post no");
    const std::string out = ::testing::internal::GetCapturedStdout();
    std::string said;
    const std::regex note("damp auto damps the parasitic mode over 1000 steps ((from step \\d+)|"
                          "in this run)");
    for (auto it = std::sregex_iterator(out.begin(), out.end(), note); it != std::sregex_iterator();
         ++it)
      said += (said.empty() ? "" : "; ") + (*it)[1].str();
    return said;
  };
  EXPECT_EQ(told("midpoint", "langevin 1.0 1.0 0.5 4711", 1), "in this run");
  // from the thermostat's first change on; a second run goes on damping
  EXPECT_EQ(told("lobatto 3", "temp/berendsen 1.0 1.0 0.1", 2), "from step 2; in this run");
  EXPECT_EQ(told("midpoint", "momentum 5 linear 1 1 1", 1), "");
  EXPECT_EQ(told("lobatto 2", "langevin 1.0 1.0 0.5 4711", 1), "");
  EXPECT_EQ(told("midpoint damp 0", "langevin 1.0 1.0 0.5 4711", 1), "");
}

/* ----------------------------------------------------------------------
   a step that begins in the jump loop of the one before (nothing looks in
   between) is the step begun at its start: the same positions and the
   same list builds. A timeout keeps the fix from beginning steps ahead
   (the run may end before the next step) and changes nothing else. With
   neigh_modify once yes (LAMMPS checks no distances) a Lobatto step begun
   ahead must measure its nodes where they are in the step, or it asks for
   list builds that the step begun at its start does not
------------------------------------------------------------------------- */

TEST(PEJump, StepsBegunAheadCheckTheListsAsStepsBegunAtTheirStart)
{
  for (const std::string lists : {"once yes", "once no"}) {
    std::vector<double> x[2];
    LAMMPS_NS::bigint builds[2];
    for (int timeout = 0; timeout < 2; ++timeout) {
      Sim s;
      lj_liquid(s, 5);
      s.cmds({"neigh_modify " + lists, "fix int all pe_jump quadrature lobatto 3", "timestep 0.002",
              "thermo 10"});
      if (timeout) s.cmd("timer timeout 10:00:00 every 1");
      s.cmd("run 300");
      x[timeout] = positions(s);
      builds[timeout] = s.lmp->neighbor->ncalls;
    }
    EXPECT_EQ(max_diff(x[0], x[1]), 0.0) << lists;
    EXPECT_EQ(builds[0], builds[1]) << lists;
  }
}

/* ----------------------------------------------------------------------
   a run stopped from inside a step ends at that step's node, exactly as
   a run of that many steps, also where the fix begins steps ahead
------------------------------------------------------------------------- */

TEST(PEJump, RunStoppedInsideAStepEndsAtItsNode)
{
  std::vector<double> stopped, plain;
  for (const bool stop : {true, false}) {
    Sim s;
    lj_liquid(s);
    (*s.lmp->modify->fix_map)["stop/at"] = &stop_at_creator;
    s.cmds({"fix 1 all pe_jump", "timestep 0.005", "thermo 0"});
    if (stop)
      s.cmds({"fix 2 all stop/at 60", "run 100 post no"});
    else
      s.cmd("run 60 post no");
    EXPECT_EQ(s.lmp->update->ntimestep, 60);
    (stop ? stopped : plain) = lj_state(s);
  }
  ASSERT_EQ(stopped.size(), plain.size());
  double d = 0.0;
  for (size_t i = 0; i < plain.size(); ++i) d = std::max(d, std::fabs(stopped[i] - plain[i]));
  EXPECT_EQ(d, 0.0);
}

TEST(PEJump, SplitRunsAndRestartsAreExact)
{
  for (const std::string rule : {"midpoint", "lobatto 3", "legendre 2"}) {
    const std::string fix = "fix 1 all pe_jump quadrature " + rule;
    std::vector<double> unbroken, split, restarted;
    {
      Sim s;
      lj_liquid(s);
      s.cmds({fix, "timestep 0.005", "thermo 50", "run 200 post no"});
      unbroken = lj_state(s);
    }
    {
      Sim s;
      lj_liquid(s);
      s.cmds({fix, "timestep 0.005", "thermo 50", "run 100 post no", "run 100 post no"});
      split = lj_state(s);
    }
    {
      Sim s;
      lj_liquid(s);
      s.cmds({fix, "timestep 0.005", "thermo 50", "run 100 post no",
              "write_restart pe_jump_split.restart", "clear", "read_restart pe_jump_split.restart",
              "neighbor 0.3 bin", "neigh_modify every 1 delay 0 check yes", fix, "thermo 50",
              "run 100 post no"});
      restarted = lj_state(s);
      std::remove("pe_jump_split.restart");
    }
    ASSERT_EQ(unbroken.size(), split.size());
    double dsplit = 0.0, drestart = 0.0;
    for (size_t i = 0; i < unbroken.size(); ++i) {
      dsplit = std::max(dsplit, std::fabs(split[i] - unbroken[i]));
      drestart = std::max(drestart, std::fabs(restarted[i] - unbroken[i]));
    }
    // the neighbor lists rebuilt at the start of a run change the summation
    // order of the forces, as for fix nve: agreement to round-off
    EXPECT_LT(dsplit, 1e-12) << rule;
    EXPECT_LT(drestart, 1e-12) << rule;
  }
}

// damp auto starts damping the parasitic mode at the first velocity change
// by a thermostat (here fix temp/rescale at step 50); a split run or a
// restart went on undamped until the thermostat's next action (1.7e-5 off
// the unbroken run on LAMMPS' Couette example, fix nve 4e-15)
TEST(PEJump, SplitRunsAndRestartsKeepTheDampingOfAThermostat)
{
  for (const std::string rule : {"midpoint", "lobatto 3"}) {
    const std::vector<std::string> fixes = {"fix 1 all pe_jump quadrature " + rule,
                                            "fix 2 all temp/rescale 50 1.0 1.0 0.02 1.0"};
    const auto state = [&](const std::vector<std::string> &runs) {
      Sim s;
      lj_liquid(s);
      s.cmds(fixes);
      s.cmds({"timestep 0.005", "thermo 50"});
      s.cmds(runs);
      return lj_state(s);
    };
    const auto unbroken = state({"run 200 post no"});
    const auto split = state({"run 101 post no", "run 99 post no"});
    std::vector<std::string> restart = {"run 101 post no",
                                        "write_restart pe_jump_damp.restart",
                                        "clear",
                                        "read_restart pe_jump_damp.restart",
                                        "neighbor 0.3 bin",
                                        "neigh_modify every 1 delay 0 check yes"};
    restart.insert(restart.end(), fixes.begin(), fixes.end());
    restart.insert(restart.end(), {"thermo 50", "run 99 post no"});
    const auto restarted = state(restart);
    std::remove("pe_jump_damp.restart");
    ASSERT_EQ(unbroken.size(), split.size());
    ASSERT_EQ(unbroken.size(), restarted.size());
    EXPECT_LT(max_diff(unbroken, split), 1e-12) << rule;
    EXPECT_LT(max_diff(unbroken, restarted), 1e-12) << rule;
  }
}

// the damping remembers a velocity change beside a thermostat only: fix
// momentum in a first run (no thermostat), fix temp/rescale (every 100
// steps) in the second leave the second run undamped until the thermostat
// acts (it was damped from its first step)
TEST(PEJump, DampingIsNotRememberedFromRunsWithoutThermostat)
{
  const auto state = [](const std::string &second) {
    Sim s;
    lj_liquid(s);
    s.cmds({"fix 1 all pe_jump", "fix 2 all momentum 50 linear 1 1 1", "timestep 0.005", "thermo 0",
            "run 250 post no", "unfix 2"});
    if (!second.empty()) s.cmd(second);
    s.cmd("run 49 post no");
    return lj_state(s);
  };
  EXPECT_EQ(max_diff(state("fix 3 all temp/rescale 100 1.0 1.0 0.02 1.0"), state("")), 0.0);
}

// with "neigh_modify check no" the lists are rebuilt every N steps whatever
// the atoms do; a run continued from a restart (lists built at the node
// q^n) reproduces the unbroken run only if that one built its lists at the
// nodes too, as fix nve does
TEST(PEJump, RestartUnderNeighCheckNoIsExact)
{
  for (const std::string rule : {"nve", "midpoint", "lobatto 3", "legendre 2"}) {
    const std::string fix = (rule == "nve") ? "fix 1 all nve"
                                            : "fix 1 all pe_jump quadrature " + rule;
    const std::string lists = "neigh_modify every 10 delay 0 check no";
    std::vector<double> unbroken, restarted;
    {
      Sim s;
      lj_liquid(s, 6);
      s.cmds({lists, fix, "timestep 0.005", "thermo 0", "run 2000 post no"});
      unbroken = lj_state(s);
    }
    {
      Sim s;
      lj_liquid(s, 6);
      s.cmds({lists, fix, "timestep 0.005", "thermo 0", "run 1000 post no",
              "write_restart pe_jump_checkno.restart", "clear",
              "read_restart pe_jump_checkno.restart", "neighbor 0.3 bin", lists, fix, "thermo 0",
              "run 1000 post no"});
      restarted = lj_state(s);
      std::remove("pe_jump_checkno.restart");
    }
    double d = 0.0;
    for (size_t i = 0; i < unbroken.size(); ++i)
      d = std::max(d, std::fabs(restarted[i] - unbroken[i]));
    EXPECT_EQ(d, 0.0) << rule;
  }
}

TEST(PEJump, VelocityChangeRestartsSchemeWithLogMessage)
{
  Sim s(MPI_COMM_WORLD, false);
  harmonic_ring(s, 10, 50.0, 1.0, 5);
  s.cmds({"fix 1 all pe_jump", "timestep 0.01", "thermo 0", "run 100 post no"});
  ::testing::internal::CaptureStdout();
  s.cmd("run 10 post no");
  std::string quiet = ::testing::internal::GetCapturedStdout();
  EXPECT_THAT(quiet, ::testing::Not(ContainsRegex("velocities were changed")));
  s.cmd("velocity all scale 2.0");
  ::testing::internal::CaptureStdout();
  s.cmd("run 10 post no");
  std::string out = ::testing::internal::GetCapturedStdout();
  EXPECT_THAT(out, ContainsRegex("velocities were changed since the last run"));
  // restarted with init kick: the node velocities are the new ones, the
  // jump equals h F/m again, so the jump energy matches a fresh start
}

namespace {
// the time step of fix pe_jump/async K is the coarse step of K fine steps:
// K for it, 1 for the other fixes (the tests below that run both take the
// same time with K times fewer steps of K times the step)
int async_K(const std::string &fix)
{
  const auto at = fix.find("pe_jump/async ");
  return (at == std::string::npos) ? 1 : std::stoi(fix.substr(at + 14));
}
}    // namespace

/* ----------------------------------------------------------------------
   atoms deleted between runs: the jumps of their partners hold forces of
   interactions that are gone; the scheme restarts (log message), and the
   total momentum stays what it was, as with fix nve (with the stale jumps
   it changed by about 1e-2). Both fixes
------------------------------------------------------------------------- */

TEST(PEJump, DeletedAtomsRestartTheScheme)
{
  const auto momentum = [](Sim &s) {
    return std::vector<double>{s.eval("vcm(all,x)*mass(all)"), s.eval("vcm(all,y)*mass(all)"),
                               s.eval("vcm(all,z)*mass(all)")};
  };
  for (const std::string fix :
       {"fix 1 all nve", "fix 1 all pe_jump", "fix 1 all pe_jump quadrature lobatto 3",
        "fix 1 all pe_jump/async 5 fast", "fix 1 all pe_jump/async 5 fast quadrature lobatto 3"}) {
    const int K = async_K(fix);
    for (const int first : {505 / K, 503 / K}) {
      Sim s(MPI_COMM_WORLD, false);
      lj_liquid(s);
      s.cmds({"region f sphere 3.36 3.36 3.36 2.0 units box", "group fast region f", fix,
              fmt::format("timestep {}", 0.002 * K), "thermo 0",
              fmt::format("run {} post no", first), "region gone sphere 5.5 5.5 5.5 0.8 units box",
              "delete_atoms region gone"});
      ASSERT_LT(s.lmp->atom->natoms, 256) << fix;
      ::testing::internal::CaptureStdout();
      s.cmd("run 0 post no");
      const std::string out = ::testing::internal::GetCapturedStdout();
      if (fix.find("pe_jump") != std::string::npos)
        EXPECT_THAT(out,
                    ContainsRegex("the group had [0-9]+ atoms at the end of the last run "
                                  "and has [0-9]+ now"))
            << fix;
      const auto before = momentum(s);
      s.cmd(fmt::format("run {} post no", 20 / K));
      const auto after = momentum(s);
      EXPECT_LT(max_diff(before, after), 1e-12) << fix << ", deleted after step " << first;
    }
  }
}

/* ----------------------------------------------------------------------
   atoms deleted and others created between runs: the message gives both
   counts, not their difference as a number deleted (6 deleted and 2
   created read as "4 atoms ... deleted" before)
------------------------------------------------------------------------- */

TEST(PEJump, DeletedAndCreatedAtomsAreToldByTheirCounts)
{
  for (const std::string fix : {"pe_jump", "pe_jump/async 5 fast"}) {
    Sim s(MPI_COMM_WORLD, false);
    lj_liquid(s);
    s.cmds({"group fast id 1:20", "fix 1 all " + fix, "timestep 0.01", "thermo 0", "run 5 post no",
            "group gone id 101:106", "delete_atoms group gone",
            "create_atoms 1 single 0.1 0.1 0.1 units box",
            "create_atoms 1 single 2.0 2.0 0.1 units box"});
    ::testing::internal::CaptureStdout();
    s.cmd("run 0 post no");
    const std::string out = ::testing::internal::GetCapturedStdout();
    EXPECT_THAT(out,
                ContainsRegex("the group had 256 atoms at the end of the last run and has "
                              "252 now"))
        << fix;
    EXPECT_THAT(out, ::testing::Not(ContainsRegex("4 atoms"))) << fix;
  }
}

namespace {
// the LJ liquid with a fast sphere: the commands before, a change between
// runs, then 20 steps of 0.002 (pe_jump/async K: 20/K of 0.002 K), once
// with the fix continued (its log must say why the scheme restarts) and
// once with the fix defined anew after the change; the largest difference
// of the positions
double continued_against_redefined(const std::string &fix, const std::vector<std::string> &before,
                                   const std::string &change, const std::string &why)
{
  const int K = async_K(fix);
  std::vector<double> x[2];
  for (const int redefine : {0, 1}) {
    Sim s(MPI_COMM_WORLD, false);
    lj_liquid(s);
    s.cmds({"region f sphere 3.36 3.36 3.36 2.0 units box", "group fast region f",
            "fix 1 all " + fix, fmt::format("timestep {}", 0.002 * K), "thermo 0"});
    s.cmds(before);
    // a change of several commands is written with ';' between them
    for (std::size_t at = 0, end = 0; at < change.size(); at = end + 1) {
      end = std::min(change.find(';', at), change.size());
      s.cmd(change.substr(at, end - at));
    }
    if (redefine) s.cmds({"unfix 1", "fix 1 all " + fix});
    ::testing::internal::CaptureStdout();
    s.cmd(fmt::format("run {} post no", 20 / K));
    const std::string out = ::testing::internal::GetCapturedStdout();
    if (!redefine) EXPECT_THAT(out, ContainsRegex(why)) << fix;
    x[redefine] = unwrapped_positions(s);
  }
  return max_diff(x[0], x[1]);
}
}    // namespace

/* ----------------------------------------------------------------------
   an energy minimization between runs moves the atoms and leaves the
   velocities: the jumps (and Lobatto start-node forces) belong to the old
   positions. The scheme restarts (log message), so that the run goes on
   as with the fix defined anew after the minimization (with the stale
   state: 1e-2 off with lobatto 2)
------------------------------------------------------------------------- */

TEST(PEJump, MinimizationBetweenRunsRestartsTheScheme)
{
  for (const std::string fix :
       {"pe_jump", "pe_jump quadrature lobatto 2", "pe_jump quadrature lobatto 3",
        "pe_jump/async 5 fast", "pe_jump/async 5 fast quadrature lobatto 3"})
    EXPECT_LT(continued_against_redefined(fix, {fmt::format("run {} post no", 50 / async_K(fix))},
                                          "minimize 0 1e-8 20 20",
                                          "energy minimization since the last run"),
              1e-12)
        << fix;
}

/* ----------------------------------------------------------------------
   a new force field between runs (pair_coeff, pair_style, a box changed
   without moving the atoms, ...): the jumps hold h F/m of the old forces
   and would leave an alternating jump of h (F' - F)/m (LJ liquid, epsilon
   1 -> 1.5 after 500 steps: etotal alternating by 5.2e-3 from step to
   step, fix nve spreads by 1.1e-3). The potential energy at the positions
   the last run ended at tells it: the scheme restarts (log message), as a
   fix defined anew; also when the thermo output does not ask for the
   energy, and not when nothing changed
------------------------------------------------------------------------- */

TEST(PEJump, NewForceFieldBetweenRunsRestartsTheScheme)
{
  const std::string why =
      "the potential energy at the current positions changed since the last run";
  for (const std::string fix :
       {"pe_jump", "pe_jump quadrature lobatto 2", "pe_jump quadrature lobatto 3",
        "pe_jump quadrature legendre 2", "pe_jump/async 5 fast",
        "pe_jump/async 5 fast quadrature lobatto 3"}) {
    const int K = async_K(fix);
    const std::string run50 = fmt::format("run {} post no", 50 / K);
    for (const std::string change :
         {"pair_coeff 1 1 1.5 1.0 2.5", "pair_style soft 1.0;pair_coeff 1 1 20.0",
          "pair_style lj/cut 2.2;pair_coeff 1 1 1.0 1.0 2.2"})
      EXPECT_LT(continued_against_redefined(fix, {run50}, change, why), 1e-12)
          << fix << ", " << change;
    // no energy in the thermo output: the fix asks for it at the run's last step
    EXPECT_LT(continued_against_redefined(fix, {"thermo_style custom step temp", run50},
                                          "pair_coeff 1 1 1.5 1.0 2.5", why),
              1e-12)
        << fix;
    // nothing changed (and new neighbor lists sum the energy in another order)
    Sim s(MPI_COMM_WORLD, false);
    lj_liquid(s);
    s.cmds({"region f sphere 3.36 3.36 3.36 2.0 units box", "group fast region f",
            "fix 1 all " + fix, fmt::format("timestep {}", 0.002 * K), "thermo 0", run50,
            "pair_coeff 1 1 1.0 1.0 2.5", "atom_modify sort 1 1.0", "run 0 post no",
            "atom_modify sort 1000 0.0"});
    ::testing::internal::CaptureStdout();
    s.cmd(fmt::format("run {} post no", 20 / K));
    const std::string out = ::testing::internal::GetCapturedStdout();
    EXPECT_THAT(out, ::testing::Not(ContainsRegex("restarts"))) << fix;
  }
}

/* ----------------------------------------------------------------------
   the census of a run's end travels in restart files written between
   runs: a force field or masses changed after read_restart restart the
   scheme as in one session (LAMMPS itself refuses to move atoms there;
   a new pair_coeff there was not seen: 1.6e-2 relative in the thermo
   output against the fix defined anew), and an
   unchanged continuation stays exact (no restart)
------------------------------------------------------------------------- */

TEST(PEJump, ChangesAfterReadRestartRestartTheScheme)
{
  const std::string file = "pe_jump_census.restart";
  for (const std::string fix :
       {"pe_jump", "pe_jump quadrature lobatto 3", "pe_jump/async 5 fast"}) {
    const int K = async_K(fix);
    {
      Sim s;
      lj_liquid(s);
      s.cmds({"region f sphere 3.36 3.36 3.36 2.0 units box", "group fast region f",
              "fix 1 all " + fix, fmt::format("timestep {}", 0.002 * K), "thermo 0",
              fmt::format("run {} post no", 50 / K), "write_restart " + file});
    }
    for (const std::string change : {"", "pair_coeff 1 1 1.5 1.0 2.5", "mass 1 1.5"}) {
      std::vector<double> x[2];
      std::string out[2];
      for (const int anew : {0, 1}) {
        Sim s(MPI_COMM_WORLD, false);
        ::testing::internal::CaptureStdout();
        EXPECT_EQ(error_from([&] {
                    s.cmds({"read_restart " + file, "neighbor 0.3 bin",
                            "neigh_modify every 1 delay 0 check yes", "thermo 0",
                            "fix 1 all " + fix});
                    if (anew) s.cmd("unfix 1");
                    if (!change.empty()) s.cmd(change);
                    if (anew) s.cmd("fix 2 all " + fix);
                    s.cmd(fmt::format("run {} post no", 20 / K));
                  }),
                  "no error")
            << fix << ", " << change;
        out[anew] = ::testing::internal::GetCapturedStdout();
        x[anew] = unwrapped_positions(s);
      }
      if (change.empty()) {
        EXPECT_THAT(out[0], ::testing::Not(ContainsRegex("restarts"))) << fix;
      } else {
        EXPECT_THAT(out[0], ContainsRegex("since the last run")) << fix << ", " << change;
        EXPECT_LT(max_diff(x[0], x[1]), 1e-12) << fix << ", " << change;
      }
    }
    std::remove(file.c_str());
  }
}

/* ----------------------------------------------------------------------
   atoms that join the group between runs have no jump yet: the scheme
   restarts (log message), and the total momentum stays what it was
------------------------------------------------------------------------- */

TEST(PEJump, AtomsJoiningTheGroupRestartTheScheme)
{
  for (const std::string fix :
       {"pe_jump", "pe_jump quadrature lobatto 2", "pe_jump quadrature lobatto 3"}) {
    Sim s(MPI_COMM_WORLD, false);
    lj_liquid(s);
    s.cmds({"region half block INF 3.36 INF INF INF INF units box", "group mob region half",
            "fix 1 mob " + fix, "timestep 0.002", "thermo 0", "run 50 post no",
            "group mob union mob all"});
    ::testing::internal::CaptureStdout();
    s.cmd("run 0 post no");
    const std::string out = ::testing::internal::GetCapturedStdout();
    EXPECT_THAT(out,
                ContainsRegex("the group had [0-9]+ atoms at the end of the last run and "
                              "has 256 now"))
        << fix;
    const double p0 = s.eval("vcm(all,x)*mass(all)");
    s.cmd("run 20 post no");
    EXPECT_NEAR(s.eval("vcm(all,x)*mass(all)"), p0, 1e-12) << fix;
  }
}

/* ----------------------------------------------------------------------
   atoms moved by a command between runs (displace_atoms): the jumps
   belong to the old positions, the scheme restarts (log message) and the
   run equals one with the fix defined anew; wrapping atoms into the box
   (balance, the next run's setup) is no move
------------------------------------------------------------------------- */

TEST(PEJump, AtomsMovedBetweenRunsRestartTheScheme)
{
  for (const std::string fix :
       {"pe_jump", "pe_jump quadrature lobatto 3", "pe_jump/async 5 fast"}) {
    const int K = async_K(fix);
    const std::vector<std::string> before = {fmt::format("run {} post no", 300 / K),
                                             "balance 1.0 shift x 5 1.1"};
    {
      Sim s(MPI_COMM_WORLD, false);
      lj_liquid(s);
      s.cmds({"region f sphere 3.36 3.36 3.36 2.0 units box", "group fast region f",
              "fix 1 all " + fix, fmt::format("timestep {}", 0.002 * K), "thermo 0"});
      s.cmds(before);
      ::testing::internal::CaptureStdout();
      s.cmd(fmt::format("run {} post no", 5 / K));
      const std::string quiet = ::testing::internal::GetCapturedStdout();
      EXPECT_THAT(quiet, ::testing::Not(ContainsRegex("restarts"))) << fix;
    }
    EXPECT_LT(continued_against_redefined(
                  fix, before, "displace_atoms all random 0.01 0.01 0.01 4711",
                  "atoms of the group were moved \\(or renumbered\\) since the last run"),
              1e-12)
        << fix;
  }
}

/* ----------------------------------------------------------------------
   a new time step between runs: the jumps, h F/m of the old step, would
   leave an alternating jump of (h' - h) F/m, which shows in etotal; the
   scheme restarts (log message), as a fix defined anew, unless compensate
   is given (then the jumps are carried over, e.g. to keep the
   pseudo-energy). Likewise new masses. etotal then spreads as fix nve's
------------------------------------------------------------------------- */

TEST(PEJump, NewTimeStepOrMassesBetweenRunsRestartTheScheme)
{
  // spread of etotal over 50 steps after the change
  const auto spread_after = [](Sim &s) {
    double lo = 1e300, hi = -1e300;
    for (int n = 0; n < 50; n++) {
      s.cmd("run 1 post no");
      lo = std::min(lo, s.eval("etotal"));
      hi = std::max(hi, s.eval("etotal"));
    }
    return hi - lo;
  };
  for (const std::string change : {"timestep 0.006", "mass 1 1.5"}) {
    std::map<std::string, double> spread;
    std::vector<double> x[2];
    for (const std::string fix : {"nve", "pe_jump", "pe_jump compensate no", "pe_jump redefined",
                                  "pe_jump quadrature lobatto 3"}) {
      Sim s(MPI_COMM_WORLD, false);
      lj_liquid(s);
      const std::string style = (fix == "pe_jump redefined") ? "pe_jump" : fix;
      s.cmds({"fix 1 all " + style, "timestep 0.002", "thermo 0", "run 100 post no", change});
      if (fix == "pe_jump redefined") s.cmds({"unfix 1", "fix 1 all pe_jump"});
      ::testing::internal::CaptureStdout();
      s.cmd("run 0 post no");
      const std::string out = ::testing::internal::GetCapturedStdout();
      // (compensate carries jumps over a new step only: new masses restart anyway)
      const bool restarts = (fix == "pe_jump") || (fix == "pe_jump quadrature lobatto 3") ||
          ((fix == "pe_jump compensate no") && (change[0] == 'm'));
      EXPECT_EQ(std::regex_search(out, std::regex("changed since the last run")), restarts)
          << fix << ", " << change;
      spread[fix] = spread_after(s);
      if (fix == "pe_jump") x[0] = unwrapped_positions(s);
      if (fix == "pe_jump redefined") x[1] = unwrapped_positions(s);
    }
    std::printf("%s: etotal spread nve %g, pe_jump %g, compensate no %g, lobatto 3 %g\n",
                change.c_str(), spread["nve"], spread["pe_jump"], spread["pe_jump compensate no"],
                spread["pe_jump quadrature lobatto 3"]);
    EXPECT_LT(max_diff(x[0], x[1]), 1e-12) << change;
    EXPECT_LT(spread["pe_jump"], 2.0 * spread["nve"]) << change;
    EXPECT_LT(spread["pe_jump quadrature lobatto 3"], 2.0 * spread["nve"]) << change;
  }
}

/* ----------------------------------------------------------------------
   cost: evaluations per step, checked against a pair style that counts
   its own compute() calls
------------------------------------------------------------------------- */

namespace {
class PairCounting : public LAMMPS_NS::PairLJCut {
 public:
  using PairLJCut::PairLJCut;
  static int calls;
  void compute(int eflag, int vflag) override
  {
    ++calls;
    PairLJCut::compute(eflag, vflag);
  }
};
int PairCounting::calls = 0;
LAMMPS_NS::Pair *counting_creator(LAMMPS_NS::LAMMPS *lmp)
{
  return new PairCounting(lmp);
}
}    // namespace

TEST(PEJump, ForceEvaluationsPerStep)
{
  struct Case {
    std::string rule;
    int per_step;    // evaluations on steps without energy output
    int extra;       // extra evaluation on energy output steps
  };
  for (const Case &c : {Case{"midpoint", 1, 1}, Case{"legendre 2", 2, 1}, Case{"legendre 3", 3, 1},
                        Case{"legendre 5", 5, 1}, Case{"lobatto 2", 1, 0}, Case{"lobatto 3", 2, 0},
                        Case{"lobatto 5", 4, 0}}) {
    Sim s;
    (*s.lmp->force->pair_map)["lj/cut/counting"] = &counting_creator;
    lj_liquid(s);
    s.cmds({"pair_style lj/cut/counting 2.5", "pair_coeff 1 1 1.0 1.0 2.5",
            "fix 1 all pe_jump quadrature " + c.rule, "timestep 0.005", "thermo 25",
            "run 0 post no"});
    PairCounting::calls = 0;
    s.cmd("run 100 post no");
    // 100 steps, thermo (energy) output on steps 25, 50, 75, 100, plus the setup evaluation
    const int expected = 1 + 100 * c.per_step + 4 * c.extra;
    EXPECT_EQ(PairCounting::calls, expected) << c.rule;
    EXPECT_DOUBLE_EQ(s.vec("1", 3), c.per_step + c.extra) << c.rule;    // last step has output
    EXPECT_DOUBLE_EQ(s.vec("1", 4), expected - 1) << c.rule;
  }
}

TEST(PEJump, EnergyAndPressureAreNodeValues)
{
  // on output steps pe and the virial are those of the positions q^n that
  // the run ends at: a fresh evaluation at the final positions agrees
  for (const std::string rule : {"midpoint", "lobatto 3"}) {
    Sim s;
    lj_liquid(s);
    s.cmds(
        {"fix 1 all pe_jump quadrature " + rule, "timestep 0.005", "thermo 10", "run 50 post no"});
    const double pe = s.eval("c_thermo_pe");
    const double press = s.eval("c_thermo_press");
    s.cmds({"unfix 1", "run 0 post no"});
    EXPECT_NEAR(s.eval("c_thermo_pe"), pe, 1e-10 * std::fabs(pe)) << rule;
    EXPECT_NEAR(s.eval("c_thermo_press"), press, 1e-10) << rule;
  }
}

// what reads the ghost atoms at the end of an output step (compute
// pair/local, group/group, bond/local, rdf, coord/atom) sees them at the
// step end, where the owned atoms are: the pair energy summed from the
// pairs equals evdwl. A Lobatto rule with interior nodes left the ghosts
// at its last interior node (lobatto 3: 0.61 off evdwl at h = 0.004 for
// 500 atoms, first order in h)
TEST(PEJump, GhostAtomsAreAtTheStepEndOnOutputSteps)
{
  for (const std::string rule :
       {"midpoint", "lobatto 2", "lobatto 3", "lobatto 5", "legendre 2", "auto 1e-6"}) {
    Sim s;
    lj_liquid(s, 5);
    s.cmds({"fix 1 all pe_jump quadrature " + rule, "timestep 0.004",
            "compute pl all pair/local eng", "compute spl all reduce sum c_pl inputs local",
            "region slab block INF INF INF INF INF 4.0", "group A region slab",
            "group B subtract all A", "compute gg A group/group B",
            "thermo_style custom step evdwl c_spl c_gg", "thermo_modify norm no", "thermo 10",
            "run 30 post no"});
    const double evdwl = s.eval("evdwl");
    const double pairs = s.eval("c_spl");
    const double between = s.eval("c_gg");
    // the same at the final positions, evaluated afresh
    s.cmds({"unfix 1", "run 0 post no"});
    EXPECT_NEAR(pairs, evdwl, 1e-10 * std::fabs(evdwl)) << rule;
    EXPECT_NEAR(between, s.eval("c_gg"), 1e-10 * std::fabs(between)) << rule;
  }
}

// a pair that comes within the cutoff in the last part of a dump step:
// the lists are checked up to the step end, where the dumped forces are
// evaluated (two atoms closing head-on; the dumped force was 0 instead of
// the LJ force 0.0402 at r = 2.489 with midpoint, legendre 1 and
// pe_jump/async, the lists being checked up to the last node only)
TEST(PEJump, DumpedForcesSeePairsThatEnterTheCutoffInTheStep)
{
  for (const std::string fix : {"pe_jump", "pe_jump quadrature legendre 1", "pe_jump/async 1 b",
                                "pe_jump/async 2 all", "pe_jump quadrature lobatto 2"}) {
    Sim s;
    const std::string file = "pe_jump_pair_enters.dump";
    s.cmds({"units lj",
            "atom_style atomic",
            "atom_modify map array",
            "boundary p p p",
            "region box block 0 20 0 20 0 20",
            "create_box 1 box",
            "create_atoms 1 single 5.0 10 10 units box",
            "create_atoms 1 single 7.81 10 10 units box",
            "mass 1 1.0",
            "pair_style lj/cut 2.5",
            "pair_coeff 1 1 1.0 1.0 2.5",
            "neighbor 0.3 bin",
            "neigh_modify every 1 delay 0 check yes",
            "group a id 1",
            "group b id 2",
            "velocity a set 2.2923 0 0",
            "velocity b set -2.2923 0 0",
            "timestep 0.01",
            "fix 1 all " + fix,
            "thermo 0",
            "dump d all custom 7 " + file + " id x fx",
            "dump_modify d sort id format float %.17g",
            "run 9 post no"});
    // step 7 dumps and tallies nothing (thermo at steps 0 and 9 only)
    double x[2] = {0.0, 0.0}, fx[2] = {0.0, 0.0};
    std::ifstream in(file);
    std::string line;
    while (std::getline(in, line) && (line != "7")) continue;
    while (std::getline(in, line) && (line.rfind("ITEM: ATOMS", 0) != 0)) continue;
    for (int n = 0; n < 2 && std::getline(in, line); ++n) {
      std::istringstream row(line);
      int id;
      row >> id >> x[n] >> fx[n];
    }
    std::remove(file.c_str());
    const double r = x[1] - x[0];
    const double lj = 24.0 * (2.0 * std::pow(r, -13) - std::pow(r, -7));
    ASSERT_LT(r, 2.5) << fix;
    EXPECT_NEAR(fx[1], lj, 1e-12) << fix << " r " << r;
  }
}

// bonds that break inside the force evaluation (bond style quartic): with
// Lobatto rules every evaluation of a
// step is made whatever the output, and a run with thermo output at every
// step equals one without; midpoint and Legendre rules evaluate again at
// the step end on output steps, which broke bonds that the run without
// output kept (400-atom 2d quartic network, midpoint: 0.87 apart after
// 2000 steps with thermo 1 against thermo 1000), and are refused
TEST(PEJump, BreakableBondsDoNotDependOnTheOutput)
{
  const auto network = [](const std::string &rule, int thermo) {
    Sim s;
    s.cmds({"units lj",
            "atom_style bond",
            "atom_modify map array",
            "dimension 2",
            "lattice sq 0.85",
            "region box block 0 20 0 20 -0.5 0.5",
            "create_box 1 box bond/types 1 extra/bond/per/atom 4",
            "create_atoms 1 box",
            "mass 1 1.0",
            "pair_style lj/cut 1.12",
            "pair_coeff * * 1.0 1.0",
            "pair_modify shift yes",
            "special_bonds lj 0 1 1",
            "bond_style harmonic",
            "bond_coeff 1 1.0 1.0",
            "create_bonds many all all 1 1.0 1.1",
            "special_bonds lj 1 1 1",
            "bond_style quartic",
            "bond_coeff 1 1200 -0.55 0.25 1.3 34.6878",
            "velocity all create 2.5 4711 dist gaussian",
            "neighbor 0.4 bin",
            "fix 1 all pe_jump quadrature " + rule,
            "fix 2 all enforce2d",
            "timestep 0.003",
            fmt::format("thermo {}", thermo),
            "run 600 post no"});
    return unwrapped_positions(s);
  };
  for (const std::string rule : {"lobatto 2", "lobatto 3"})
    EXPECT_LT(max_diff(network(rule, 1), network(rule, 1000)), 1e-10) << rule;
  for (const std::string rule : {"midpoint", "legendre 2"})
    EXPECT_THAT(error_from([&]() {
                  network(rule, 1);
                }),
                ContainsRegex("the bonds of bond style quartic break inside the force evaluation"))
        << rule;
}

// peridynamic pair styles advance per-bond state at every evaluation:
// peri/ves its viscoelastic history by a whole time step, so every interior
// node of a rule advanced it once more (LAMMPS' peri/ves example with
// lobatto 3: kinetic energy 541, 537, 535 below fix nve's as h halves,
// lobatto 4 twice that, without a word). Only lobatto 2 (one evaluation per
// step, at its end) runs, and it follows fix nve
TEST(PEJump, PeridynamicsTakesOneEvaluationPerStep)
{
  const auto cylinder = [](const std::string &fix) {
    return peri_indentation("peri/ves", "14.9e9 14.9e9 0.0015001 0.0005 0.25 0.5 0.001", fix, 100.0,
                            1e-7, 150);
  };
  const double nve = cylinder("nve");
  EXPECT_NEAR(cylinder("pe_jump quadrature lobatto 2"), nve, 1e-9 * nve);
  for (const std::string rule : {"midpoint", "lobatto 3", "legendre 2", "auto 1e-6"})
    EXPECT_THAT(error_from([&]() {
                  cylinder("pe_jump quadrature " + rule);
                }),
                ContainsRegex("pair style peri/ves advances the state of its bonds at every "
                              "force evaluation"))
        << rule;
}

// the computes of the TALLY package add up the pair tallies of every
// evaluation in a step: with a Lobatto rule only the MD step's evaluation
// at the step end tallies, and compute pe/tally equals evdwl (midpoint and
// Legendre rules, which evaluate again at the step end, counted every pair
// twice: -3329.5 against evdwl -1660.5, and are refused, bad_inputs.txt)
TEST(PEJump, TallyComputesCountEveryPairOnceWithLobattoRules)
{
  for (const std::string rule : {"lobatto 2", "lobatto 3", "lobatto 5", "auto 1e-6"}) {
    Sim s;
    lj_liquid(s);
    s.cmds({"fix 1 all pe_jump quadrature " + rule, "timestep 0.004", "compute pt all pe/tally all",
            "compute st all stress/tally all", "compute sts all reduce sum c_st[1]",
            "compute sa all stress/atom NULL pair", "compute sas all reduce sum c_sa[1]",
            "thermo_style custom step evdwl c_pt c_sts c_sas", "thermo_modify norm no", "thermo 10",
            "run 30 post no"});
    const double evdwl = s.eval("evdwl");
    EXPECT_NEAR(s.eval("c_pt"), evdwl, 1e-10 * std::fabs(evdwl)) << rule;
    const double stress = s.eval("c_sas");
    EXPECT_NEAR(s.eval("c_sts"), stress, 1e-10 * std::fabs(stress)) << rule;
  }
}

// the per-atom forces that a dump writes are those at the atoms' positions,
// as with fix nve: on dump steps that tally no energy the rules whose
// primary node is not the step end (midpoint, Legendre) evaluate the forces
// there, and pe_jump/async gives every atom its total force at a coarse
// node (it held the fine interactions' forces only: interior slow atoms 0).
// Checked against a fresh evaluation at the dumped positions.
TEST(PEJump, DumpedForcesAreThoseAtTheDumpedPositions)
{
  for (const std::string fix :
       {"pe_jump", "pe_jump quadrature legendre 2", "pe_jump quadrature lobatto 3",
        "pe_jump/async 5 fast", "pe_jump/async 5 fast quadrature lobatto 3"}) {
    // (pe_jump/async 5: the same times in coarse steps of 5 fine steps)
    const int K = async_K(fix);
    const std::string at = std::to_string(10 / K);
    Sim s;
    lj_liquid(s);
    const std::string file = "pe_jump_forces.dump";
    s.cmds({"group fast id 1:40", "fix 1 all " + fix, fmt::format("timestep {}", 0.004 * K),
            "thermo 100", fmt::format("dump d all custom {} {} id x y z fx fy fz", 5 / K, file),
            "dump_modify d sort id format float %.17g", fmt::format("run {} post no", 20 / K),
            "undump d"});
    // the forces at t = 0.04 as dumped, then evaluated afresh there
    std::map<int, std::array<double, 3>> dumped;
    std::ifstream in(file);
    std::string line;
    while (std::getline(in, line) && (line != at)) continue;
    while (std::getline(in, line) && (line.rfind("ITEM: ATOMS", 0) != 0)) continue;
    for (int n = 0; n < s.lmp->atom->natoms && std::getline(in, line); ++n) {
      std::istringstream row(line);
      int id;
      double x[3], f[3];
      row >> id >> x[0] >> x[1] >> x[2] >> f[0] >> f[1] >> f[2];
      dumped[id] = {f[0], f[1], f[2]};
    }
    ASSERT_EQ(dumped.size(), s.lmp->atom->natoms) << fix;
    s.cmds({"unfix 1", "read_dump " + file + " " + at + " x y z box no", "run 0 post no"});
    std::remove(file.c_str());
    double worst = 0.0, scale = 0.0;
    for (const auto &[id, f] : dumped)
      for (int k = 0; k < 3; k++) {
        const double fresh = s.lmp->atom->f[s.lmp->atom->map(id)][k];
        worst = std::max(worst, std::fabs(f[k] - fresh));
        scale = std::max(scale, std::fabs(fresh));
      }
    EXPECT_LT(worst, 1e-10 * scale) << fix;
  }
  // dumps of positions only cost no evaluation: 20 steps, a dump every 5
  // (the last step tallies energy anyway)
  const auto evaluations = [](const std::string &dump) {
    Sim s;
    lj_liquid(s);
    s.cmds({"fix 1 all pe_jump", "timestep 0.004", "thermo 100", dump, "run 20 post no"});
    return s.vec("1", 4);
  };
  EXPECT_EQ(evaluations("dump d all atom 5 pe_jump_positions.dump"), 21.0);
  EXPECT_EQ(evaluations("dump d all xyz 5 pe_jump_positions.dump"), 21.0);
  EXPECT_EQ(evaluations("dump d all custom 5 pe_jump_positions.dump id fx"), 24.0);
  std::remove("pe_jump_positions.dump");
}

/* ----------------------------------------------------------------------
   units, masses, dimensions, newton: pseudo-energy conservation holds in
   each setting (harmonic ring, midpoint is exact)
------------------------------------------------------------------------- */

TEST(PEJump, ConservesInUnitSystemsMassStylesAndNewton)
{
  for (const std::string &variant : {"real", "metal", "si", "rmass", "newton_off", "2d"}) {
    Sim s;
    if (variant == "2d") s.cmd("dimension 2");
    if (variant == "newton_off") s.cmd("newton off");
    std::string units = "lj";
    if (variant == "real" || variant == "metal" || variant == "si") units = variant;
    s.cmds({"units " + units, "atom_style bond", "atom_modify map array", "boundary p p p",
            "region box block 0 12 -5 5 -5 5",
            "create_box 1 box bond/types 1 extra/bond/per/atom 2", "mass 1 1.0"});
    if (variant == "2d") s.cmd("region box2 block 0 12 -5 5 -0.5 0.5");
    for (int i = 0; i < 12; ++i)
      s.cmd(fmt::format("create_atoms 1 single {} {} 0", i + 0.5 + 0.05 * std::sin(i), 0.0));
    s.cmds({"bond_style harmonic", "bond_coeff 1 50.0 1.0", "pair_style zero 1.0", "pair_coeff * *",
            "velocity all create 1.0 4411 loop geom"});
    s.cmd("velocity all set NULL 0.0 0.0");
    for (int i = 1; i <= 12; ++i)
      s.cmd(fmt::format("create_bonds single/bond 1 {} {}", i, i % 12 + 1));
    if (variant == "rmass") {
      s.cmd("fix rm all property/atom rmass");
      s.cmd("set atom 1*6 mass 2.0");
      s.cmd("set atom 7*12 mass 0.5");
    }
    const double h = (units == "lj") ? 0.01
                                     : (units == "real" ? 1.0 : (units == "metal" ? 0.001 : 1e-15));
    s.cmds({"fix 1 all pe_jump", fmt::format("timestep {}", h), "thermo 100", "run 0 post no"});
    const double h0 = pseudo_energy(s);
    s.cmd("run 2000 post no");
    EXPECT_LT(std::fabs(pseudo_energy(s) - h0) / std::fabs(h0), 1e-12) << variant;
    // and the dynamics is not trivial: positions moved
    EXPECT_GT(s.vec("1", 1), 0.0) << variant;
  }
}

/* ----------------------------------------------------------------------
   variable time step: fix dt/reset and adapt
------------------------------------------------------------------------- */

TEST(PEJump, ConsistentUnderFixDtReset)
{
  Sim s;
  fpu_gni(s);
  s.cmds({"fix 1 chain pe_jump quadrature lobatto 3", "timestep 0.001",
          "fix 2 chain dt/reset 1 1.0e-4 2.0e-3 0.001 units box", "thermo 1000", "run 0 post no"});
  const double h0 = pseudo_energy(s);
  s.cmd("run 20000 post no");
  EXPECT_LT(std::fabs(pseudo_energy(s) - h0) / std::fabs(h0), 1e-12);
  EXPECT_NE(s.vec("1", 2), 0.001);    // the step did change
}

TEST(PEJump, AdaptHoldsBoundAndStepGrowsBack)
{
  Sim s;
  fpu_gni(s);
  s.cmds({"fix 1 chain pe_jump quadrature lobatto 3 adapt 1e-6 1e-5 0.004", "timestep 1e-5",
          "compute ke all ke", "variable a equal abs(c_thermo_pe+f_1)",
          "variable ratio equal f_1[2]/((v_a>c_ke)*v_a+(v_a<=c_ke)*c_ke)",
          "variable dt equal f_1[3]", "fix r all vector 1 v_ratio v_dt", "thermo 0",
          "run 3000 post no"});
  auto *vec = s.lmp->modify->get_fix_by_id("r");
  double worst = 0.0, dtmin = 1e300, dtmax = 0.0;
  for (int i = 10; i < vec->size_array_rows; ++i) {
    worst = std::max(worst, vec->compute_array(i, 0));
    dtmin = std::min(dtmin, vec->compute_array(i, 1));
    dtmax = std::max(dtmax, vec->compute_array(i, 1));
  }
  std::cout << "adapt: max jump energy / bound = " << worst / 1e-6 << ", dt in [" << dtmin << ", "
            << dtmax << "]\n";
  // the bound holds after every step (with the linear extrapolation of the
  // averaged force; the previous rule that kept it constant overshot 2.2x)
  EXPECT_LT(worst, 1e-6);
  EXPECT_LT(dtmin, 0.004);    // the step shrank ...
  EXPECT_GT(dtmin, 1e-5);     // ... without cascading to dtmin
  EXPECT_GT(dtmax / dtmin, 1.5);
}

// adapt changes the time step as fix dt/reset does, so LAMMPS keeps the
// elapsed time of changing steps and refuses reset_timestep beside it
// (which would lose that time); without adapt the fix does not change it
TEST(PEJump, AdaptIsTimeDependentAsFixDtReset)
{
  for (const bool adapt : {false, true}) {
    Sim s;
    fpu_gni(s);
    s.cmds({std::string("fix 1 chain pe_jump quadrature lobatto 3") +
                (adapt ? " adapt 1e-6 1e-5 0.004" : ""),
            "timestep 1e-4", "thermo 0", "run 50 post no"});
    const double t = s.lmp->update->atime +
        (s.lmp->update->ntimestep - s.lmp->update->atimestep) * s.lmp->update->dt;
    const std::string error = error_in(s, "reset_timestep 0");
    if (adapt) {
      EXPECT_THAT(error, ContainsRegex("Cannot reset timestep with time-dependent fix pe_jump"));
      EXPECT_NE(t, 50 * 1e-4);    // the steps changed: the elapsed time is not 50 h
    } else {
      EXPECT_EQ(error, "no error");
    }
  }
}

// adapt started from a time step above what eps allows: the first step
// is cut before the initial kick, so the error follows eps. Before, the
// controller cut the step at once after a first step of the full size
// (LJ liquid, 0.002 -> 0.0013 -> 0.00064 within two steps), and with
// compensate yes the abrupt change excited the parasitic mode: the error
// grew as eps shrank (1.2e-3 at eps 6.25e-5, 2.2e-3 at 1.5625e-5; fix nve
// at 0.002 has 2.1e-4)
TEST(PEJump, AdaptStartedAboveItsBoundConvergesWithEps)
{
  const auto liquid = [](Sim &s) {
    s.cmds({"units lj", "atom_style charge", "atom_modify map array", "lattice fcc 0.8442",
            "region box block 0 4 0 4 0 4", "create_box 1 box", "create_atoms 1 box", "mass 1 1.0",
            "velocity all create 1.5 87287 loop geom", "pair_style lj/charmm/coul/charmm 2.0 2.5",
            "pair_coeff 1 1 1.0 1.0", "neighbor 0.3 bin", "neigh_modify every 1 delay 0 check yes",
            "timestep 0.005", "fix eq all nve", "run 400 post no", "unfix eq", "reset_timestep 0"});
  };
  const auto error_at = [&](double eps) {
    Sim s;
    liquid(s);
    s.cmds({fmt::format("fix 1 all pe_jump adapt {} 1e-5 0.01", eps), "timestep 0.002",
            "variable t equal time", "fix stop all halt 1 v_t >= 0.4 error continue", "thermo 0",
            "run 100000 post no"});
    const double tfinal = s.eval("time");
    const auto x = unwrapped_positions(s);
    Sim ref;
    liquid(ref);
    const int n = static_cast<int>(std::lround(tfinal / 1.25e-4));
    ref.cmds({"fix 1 all nve", fmt::format("timestep {:.17g}", tfinal / n), "thermo 0",
              fmt::format("run {} post no", n)});
    return max_diff(x, unwrapped_positions(ref));
  };
  const double coarse = error_at(6.25e-5), fine = error_at(1.5625e-5);
  std::cout << "adapt from dt 0.002: error " << coarse << " (eps 6.25e-5), " << fine
            << " (eps 1.5625e-5)\n";
  EXPECT_GT(coarse / fine, 2.5);
}

/* ----------------------------------------------------------------------
   bad input
------------------------------------------------------------------------- */

TEST(PEJump, BadInputGivesClearErrors)
{
  const std::vector<std::string> setup = {"units lj",
                                          "atom_style atomic",
                                          "region b block 0 5 0 5 0 5",
                                          "create_box 1 b",
                                          "create_atoms 1 single 1 1 1",
                                          "mass 1 1.0",
                                          "pair_style zero 2.0",
                                          "pair_coeff * *"};
  struct Case {
    std::string command, regex;
  };
  for (const Case &c : {
           Case{"fix 1 all pe_jump bogus", "Unknown fix pe_jump keyword: bogus"},
           Case{"fix 1 all pe_jump quadrature", "Illegal fix pe_jump quadrature command: missing"},
           Case{"fix 1 all pe_jump quadrature simpson",
                "Unknown fix pe_jump quadrature rule: simpson"},
           Case{"fix 1 all pe_jump quadrature lobatto", "missing argument"},
           Case{"fix 1 all pe_jump quadrature lobatto 1", "lobatto needs 2 to 5 points, got 1"},
           Case{"fix 1 all pe_jump quadrature lobatto 6", "lobatto needs 2 to 5 points, got 6"},
           Case{"fix 1 all pe_jump quadrature legendre 0", "legendre needs 1 to 5 points, got 0"},
           Case{"fix 1 all pe_jump quadrature legendre 6", "legendre needs 1 to 5 points, got 6"},
           Case{"fix 1 all pe_jump quadrature legendre two", "Expected integer parameter"},
           Case{"fix 1 all pe_jump init", "missing argument"},
           Case{"fix 1 all pe_jump damp -1", "damp needs a time >= 0 or auto"},
           Case{"fix 1 all pe_jump damp", "missing argument"},
           Case{"fix 1 all pe_jump init zero", "Unknown fix pe_jump init style: zero"},
           Case{"fix 1 all pe_jump adapt 1e-3 0.1", "missing argument"},
           Case{"fix 1 all pe_jump adapt 0 0.001 0.01", "adapt eps must be > 0"},
           Case{"fix 1 all pe_jump adapt 1e-3 0.01 0.001", "0 < dtmin <= dtmax"},
           Case{"fix 1 all pe_jump sample", "sample needs one or more of pair"},
           Case{"fix 1 all pe_jump sample springs", "sample needs one or more of pair"},
           Case{"fix 1 all pe_jump quadrature auto", "Illegal fix pe_jump quadrature auto command"},
           Case{"fix 1 all pe_jump compensate", "Illegal fix pe_jump compensate command"},
           Case{"fix 1 all pe_jump compensate maybe", "Expected boolean parameter"},
           Case{"fix 1 all pe_jump quadrature auto 0", "quadrature auto needs TOL > 0"},
           Case{"fix 1 all pe_jump quadrature auto 1e-6 sample pair",
                "quadrature auto samples all force contributions"},
       }) {
    EXPECT_THAT(error_of(setup, c.command), ContainsRegex(c.regex)) << c.command;
  }
  std::vector<std::string> respa = setup;
  respa.push_back("fix 1 all pe_jump");
  respa.push_back("run_style respa 2 2");
  EXPECT_THAT(error_of(respa, "run 1"), ContainsRegex("does not support run_style respa"));

  const std::vector<std::string> sphere = {"units lj",
                                           "atom_style sphere",
                                           "region b block 0 5 0 5 0 5",
                                           "create_box 1 b",
                                           "create_atoms 1 single 1 1 1",
                                           "pair_style zero 2.0",
                                           "pair_coeff * *",
                                           "fix 1 all pe_jump"};
  EXPECT_THAT(error_of(sphere, "run 1"), ContainsRegex("integrates point particles only"));

  // atom styles with extra per-atom forces (electron, spin, sph, dpd-meso,
  // ...: none is in this build, so an atomic style says it has them), which
  // Verlet clears at every force evaluation and their own integrators
  // integrate, are refused by both fixes
  for (const std::string fix : {"pe_jump", "pe_jump/async 5 fast"}) {
    Sim s;
    lj_liquid(s, 2);
    s.cmds({"group fast id 1", "fix 1 all " + fix});
    s.lmp->atom->avec->forceclearflag = 1;
    const std::string error = error_from([&] {
      s.cmd("run 1");
    });
    EXPECT_THAT(error, ContainsRegex("does not integrate the extra per-atom quantities")) << fix;
  }
}

/* ----------------------------------------------------------------------
   quadrature auto: per step the 3-point Lobatto rule where the embedded
   estimate of the 2-point rule's pseudo-energy defect is below TOL, else
   the 5-point rule; on a ring of Morse bonds (non-polynomial forces)
------------------------------------------------------------------------- */

namespace {
struct AutoRun {
  double worst_step;    // largest |change of H~| in one step
  double evals;         // force evaluations over the run
};

AutoRun morse_ring(const std::string &rule, int nsteps)
{
  Sim s;
  harmonic_ring(s, 16, 1.0, 1.5, 11);
  s.cmds({"bond_style morse", "bond_coeff 1 1.0 2.0 1.0", "fix 1 all pe_jump quadrature " + rule,
          "timestep 0.05", "thermo 0", "run 0 post no"});
  AutoRun r{0.0, 0.0};
  double h = pseudo_energy(s);
  for (int n = 0; n < nsteps; ++n) {
    s.cmd("run 1 pre no post no");
    const double hn = pseudo_energy(s);
    r.worst_step = std::max(r.worst_step, std::fabs(hn - h));
    h = hn;
  }
  r.evals = s.vec("1", 4);
  return r;
}
}    // namespace

TEST(PEJump, QuadratureAutoKeepsTheStepDefectBelowTol)
{
  const int n = 400;
  const auto l2 = morse_ring("lobatto 2", n);
  const auto l3 = morse_ring("lobatto 3", n);
  const auto l5 = morse_ring("lobatto 5", n);
  std::cout << "Morse ring: largest step defect lobatto 2 " << l2.worst_step << ", lobatto 3 "
            << l3.worst_step << ", lobatto 5 " << l5.worst_step << "\n";
  EXPECT_DOUBLE_EQ(l2.evals, 1.0 * n);
  EXPECT_DOUBLE_EQ(l3.evals, 2.0 * n);
  EXPECT_DOUBLE_EQ(l5.evals, 4.0 * n);
  ASSERT_GT(l2.worst_step, 100.0 * l3.worst_step);    // the rules differ visibly
  ASSERT_GT(l3.worst_step, 100.0 * l5.worst_step);

  // tolerances between the rules: every step keeps its defect below the
  // tolerance, at fewer evaluations than the fixed rule that would be needed
  struct Band {
    double tol, fewer, more;    // tolerance, evaluations per step of the rules around it
  };
  for (const Band b : {Band{0.3 * l2.worst_step, 1.0, 2.0}, Band{0.3 * l3.worst_step, 2.0, 4.0}}) {
    const auto mixed = morse_ring(fmt::format("auto {:.6g}", b.tol), n);
    std::cout << "auto " << b.tol << ": largest step defect " << mixed.worst_step << ", "
              << mixed.evals / n << " evaluations per step\n";
    EXPECT_LT(mixed.worst_step, b.tol);
    EXPECT_GT(mixed.evals, b.fewer * n);
    EXPECT_LT(mixed.evals, b.more * n);
  }
  // a loose tolerance takes the 2-point rule, an impossible one the 5-point rule
  const auto loose = morse_ring("auto 1e10", n);
  EXPECT_DOUBLE_EQ(loose.evals, 1.0 * n);
  EXPECT_NEAR(loose.worst_step, l2.worst_step, 1e-12);
  const auto tight = morse_ring("auto 1e-300", n);
  EXPECT_DOUBLE_EQ(tight.evals, 4.0 * n);
  EXPECT_NEAR(tight.worst_step, l5.worst_step, 1e-12);
}

/* ----------------------------------------------------------------------
   quadrature auto tells at the end of a run how many steps took each
   rule, for runs that took steps: not for run 0 (it printed "steps with
   lobatto 2: 0, lobatto 3: 0, lobatto 5: 0")
------------------------------------------------------------------------- */

TEST(PEJump, QuadratureAutoReportsRunsThatTakeSteps)
{
  Sim s(MPI_COMM_WORLD, false);
  lj_liquid(s, 3);
  s.cmds({"fix 1 all pe_jump quadrature auto 1e-6", "timestep 0.005", "thermo 0"});
  const auto log_of = [&](const std::string &command) {
    ::testing::internal::CaptureStdout();
    s.cmd(command);
    return ::testing::internal::GetCapturedStdout();
  };
  EXPECT_THAT(log_of("run 0"), Not(ContainsRegex("quadrature auto")));
  const std::string out = log_of("run 10");
  std::smatch m;
  ASSERT_TRUE(std::regex_search(
      out, m,
      std::regex("quadrature auto 1e-06: steps with lobatto 2: ([0-9]+), lobatto 3: ([0-9]+), "
                 "lobatto 5: ([0-9]+)")));
  EXPECT_EQ(std::stoi(m[1]) + std::stoi(m[2]) + std::stoi(m[3]), 10);
  EXPECT_THAT(log_of("run 0"), Not(ContainsRegex("quadrature auto")));
}

/* ----------------------------------------------------------------------
   compensate: step-size changes no longer feed the parasitic mode, the
   pseudo-energy stays conserved, and the scheme stays second order
------------------------------------------------------------------------- */

TEST(PEJump, CompensateStepChangesKeepsEnergyBounded)
{
  // +-50% random steps around 1e-3 (doc/theory.md, section 3), 20000 steps, three
  // sequences: the growth of H depends much on the sequence, so compare sums
  double range[2] = {0.0, 0.0};
  for (int seed : {1, 2, 3}) {
    for (int k = 0; k < 2; ++k) {
      Sim s;
      fpu_gni(s);
      s.cmd(std::string("fix 1 chain pe_jump quadrature lobatto 3 compensate ") +
            (k ? "yes" : "no"));
      s.cmd("compute ke chain ke");
      s.cmd("thermo_modify norm no");
      std::mt19937 gen(seed);
      std::uniform_real_distribution<double> dt(0.0005, 0.0015);
      bool first = true;
      double e0 = 0.0, worst_h = 0.0;
      const double worst = single_steps(s, 20000, [&] {
        if (first) e0 = discrete_energy(s);
        first = false;
        worst_h = std::max(worst_h, std::fabs(discrete_energy(s) - e0));
        return dt(gen);
      });
      EXPECT_LT(worst, 1e-11) << k;    // pseudo-energy conserved either way
      std::cout << "FPU, +-50% random steps (seed " << seed << "), max |H - H0| "
                << (k ? "with" : "without") << " compensation: " << worst_h << "\n";
      range[k] += worst_h;
    }
  }
  EXPECT_LT(range[1], 0.1 * range[0]);
}

TEST(PEJump, CompensateKeepsSecondOrderWithVariableSteps)
{
  // steps h(t) = h0 (1 + 0.5 sin(2 pi t / T)), the last one cut to end at T
  const double T = 0.5;
  auto final_q = [&](double h0, const std::string &opts) {
    Sim s;
    fpu_gni(s);
    s.cmds({"fix 1 chain pe_jump quadrature lobatto 3 " + opts, "thermo 0",
            fmt::format("timestep {:.17g}", h0), "run 0 post no"});
    double t = 0.0;
    while (t < T * (1.0 - 1e-14)) {
      double h = h0 * (1.0 + 0.5 * std::sin(2.0 * M_PI * t / T));
      if (t + h > T) h = T - t;
      s.cmd(fmt::format("timestep {:.17g}", h));
      s.cmd("run 1 pre no post no");
      t += h;
    }
    std::vector<double> q;
    for (int i = 2; i <= 7; ++i) q.push_back(s.x(i, 0));
    return q;
  };
  for (const std::string opts : {"compensate no", "compensate yes"}) {
    const auto ref = final_q(T / 20000, opts);
    std::vector<double> err;
    for (int n : {250, 500, 1000}) {
      const auto q = final_q(T / n, opts);
      double e = 0.0;
      for (size_t i = 0; i < q.size(); ++i) e = std::max(e, std::fabs(q[i] - ref[i]));
      err.push_back(e);
    }
    const double order = std::log2(err[1] / err[2]);
    std::cout << opts << ": errors " << err[0] << " " << err[1] << " " << err[2] << ", order "
              << std::log2(err[0] / err[1]) << " " << order << "\n";
    EXPECT_NEAR(order, 2.0, 0.15) << opts;
  }
}

/* ----------------------------------------------------------------------
   k-space styles that zero their energy and virial at every call
   (ewald/disp, pppm/disp): the evaluations at the interior nodes of a
   Lobatto rule tally nothing and must leave the tallies of the step end
   (before: elong 0 and pe -3.83 instead of -7.16 per atom from step 1, and
   a split run restarted the scheme as if the force field had changed)
------------------------------------------------------------------------- */

TEST(PEJump, KSpaceTalliesAreThoseOfTheStepEnd)
{
  struct Style {
    std::string pair, kspace, modify;
  };
  const std::vector<Style> styles = {
      {"lj/long/coul/long long long 3.0", "ewald/disp 1e-5", ""},
      {"lj/long/coul/long long long 3.0", "pppm/disp 1e-5",
       "kspace_modify gewald/disp 0.9 mesh/disp 12 12 12 order/disp 5"},
      {"lj/cut/coul/long 3.0", "ewald 1e-5", ""}};
  for (const auto &style : styles) {
    for (const std::string rule : {"lobatto 3", "auto 1e-3", "midpoint"}) {
      Sim s;
      s.cmds({"units lj", "atom_style charge", "lattice fcc 0.8442", "region box block 0 3 0 3 0 3",
              "create_box 2 box", "create_atoms 1 box", "set type 1 type/ratio 2 0.5 87287",
              "set type 1 charge 0.5", "set type 2 charge -0.5", "mass * 1.0",
              "pair_style " + style.pair, "pair_coeff * * 1.0 1.0",
              "kspace_style " + style.kspace});
      if (!style.modify.empty()) s.cmd(style.modify);
      s.cmds({"velocity all create 1.5 87287 dist gaussian", "fix 1 all pe_jump quadrature " + rule,
              "timestep 0.005", "thermo_style custom step pe elong press", "thermo 5",
              "run 10 post no"});
      const double pe = s.eval("pe"), elong = s.eval("elong"), press = s.eval("press");
      // the same positions evaluated anew by the setup of a run of no steps
      s.cmd("run 0 post no");
      const std::string what = style.kspace + ", " + rule;
      EXPECT_LT(elong, -0.01) << what;
      EXPECT_NEAR(s.eval("elong"), elong, 1e-9 * std::fabs(elong)) << what;
      EXPECT_NEAR(s.eval("pe"), pe, 1e-9 * std::fabs(pe)) << what;
      EXPECT_NEAR(s.eval("press"), press, 1e-8 * std::fabs(press)) << what;
    }
  }
}
