/* ----------------------------------------------------------------------
   LAMMPS - Large-scale Atomic/Molecular Massively Parallel Simulator
   https://www.lammps.org/, Sandia National Laboratories
   LAMMPS development team: developers@lammps.org

   Copyright (2003) Sandia Corporation.  Under the terms of Contract
   DE-AC04-94AL85000 with Sandia Corporation, the U.S. Government retains
   certain rights in this software.  This software is distributed under
   the GNU General Public License.

   See the README file in the top-level LAMMPS directory.
------------------------------------------------------------------------- */

#include "pe_jump_step_control.h"

#include "atom.h"
#include "comm.h"
#include "fix.h"
#include "force.h"
#include "modify.h"
#include "output.h"
#include "pair.h"
#include "pe_jump_atom_state.h"
#include "update.h"
#include "utils.h"

#include <cmath>

using namespace LAMMPS_NS;
using namespace LAMMPS_NS::PEJump;

static constexpr double ADAPT_GROWTH = 1.05;    // largest step growth factor per step
static constexpr double ADAPT_SAFETY = 0.5;     // aim at this fraction of the bound
static constexpr int ADAPT_SAMPLES = 64;        // trial steps between dtmax and dtmin
static constexpr int ADAPT_BISECT = 40;         // bisections of the largest admissible step

/* ---------------------------------------------------------------------- */

StepControl::StepControl(LAMMPS *lmp, AtomState &table, double adapt_eps, double adapt_dtmin,
                         double adapt_dtmax, bool compensate) :
    Pointers(lmp),
    state(table), eps(adapt_eps), dtmin(adapt_dtmin), dtmax(adapt_dtmax), energy_scale(0.0),
    compensating(compensate), hist1(-1), hist2(-1), hlast(0.0), hlast2(0.0)
{
  if (adapts() || compensating) {
    hist1 = state.add("fhist1", 3, 0.0);
    hist2 = state.add("fhist2", 3, 0.0);
  }
}

/* ---------------------------------------------------------------------- */

double StepControl::mass_of(int i) const
{
  return atom->rmass ? atom->rmass[i] : atom->mass[atom->type[i]];
}

/* ---------------------------------------------------------------------- */

void StepControl::start_run(const char *style, double pseudo_energy)
{
  if (!adapts()) return;
  bring_into_range(style);
  energy_scale = fabs(pseudo_energy);
}

/* ---------------------------------------------------------------------- */

void StepControl::bring_into_range(const char *style)
{
  const double dt = MIN(MAX(update->dt, dtmin), dtmax);
  if (dt == update->dt) return;
  if (comm->me == 0)
    utils::logmesg(lmp, "Fix {}: timestep {} is outside the adapt range [{}, {}]: using {}\n",
                   style, update->dt, dtmin, dtmax, dt);
  set_timestep(dt);
}

/* ---------------------------------------------------------------------- */

void StepControl::first_step(const char *style, const AtomSet &set, double **f, double pe)
{
  if (!adapts()) return;
  double **v = atom->v;
  double local[2] = {0.0, 0.0}, sum[2];    // sum m |a|^2, sum m |v|^2
  set.each(atom->mask, atom->nlocal, [&](int i) {
    const double m = mass_of(i);
    for (int k = 0; k < 3; k++) {
      const double a = force->ftm2v * f[i][k] / m;
      local[0] += m * a * a;
      local[1] += m * v[i][k] * v[i][k];
    }
  });
  MPI_Allreduce(local, sum, 2, MPI_DOUBLE, MPI_SUM, world);
  const double kinetic = 0.5 * force->mvv2e * sum[1];
  const double scale = MAX(fabs(pe + kinetic), kinetic);
  const double target = 8.0 * ADAPT_SAFETY * eps * scale / force->mvv2e;
  bring_into_range(style);
  const double range = update->dt;
  if (!(sum[0] > 0.0) || (range * range * sum[0] <= target)) return;
  const double dt = MAX(sqrt(target / sum[0]), dtmin);
  if (dt == range) return;
  if (comm->me == 0)
    utils::logmesg(lmp,
                   "Fix {}: the first step takes {:.8g} instead of {:.8g}, so that the jump "
                   "energy of the initial kick stays within the adapt bound\n",
                   style, dt, range);
  set_timestep(dt);
}

/* ----------------------------------------------------------------------
   with steps h_{n-1}, h_n, h_{n+1} the smooth solution of the jump
   relation is [v]^n = (h_{n-1} + h_n)/2 a(t_n); the jump [v]^{n+1} =
   2 h_n A_n - [v]^n of the last step (A_n its averaged acceleration) falls
   short of it by
     d = (h_{n+1} - h_n)/2 a(t_{n+1}) - (h_n - h_{n-1})/2 a(t_n),
   which feeds the parasitic period-2 mode whenever the step size changes.
   Add d, with a(t_n), a(t_{n+1}) interpolated linearly from the averages
   A_{n-1}, A_n of the last two steps (at their mid-step times), less the
   part along the peculiar velocities w = v^{n+1/2} - V_cm that would
   change the pseudo-energy (1/2) sum m v^{n+1/2}.v^{n+3/2}; the total
   momentum is kept too, since sum m a = 0 and sum m w = 0.
------------------------------------------------------------------------- */

bool StepControl::compensate(double h, const AtomSet &set, double **vhalf, double **jump,
                             double **scratch)
{
  if (!compensating || !(hlast2 > 0.0)) return false;
  const double h0 = hlast2, h1 = hlast, h2 = h;    // h_{n-1}, h_n, h_{n+1}
  if ((h2 - h1 == 0.0) && (h1 - h0 == 0.0)) return false;
  const double slope = 1.0 / (0.5 * (h0 + h1));    // per (A_n - A_{n-1})
  const double c_end = 0.5 * (h2 - h1), c_start = 0.5 * (h1 - h0);
  const double ftm2v = force->ftm2v;
  double **fhist1 = state.vec(hist1);
  double **fhist2 = state.vec(hist2);

  // d (velocity units) into scratch; sums m of: v.d, v.v, and sum m v, sum m
  double local[6] = {0.0, 0.0, 0.0, 0.0, 0.0, 0.0};
  const auto deficit = [&](int i) {
    const double m = mass_of(i);
    const double minv = 1.0 / m;
    for (int k = 0; k < 3; k++) {
      const double an = ftm2v * minv * fhist1[i][k];
      const double ds = 0.5 * h1 * slope * (an - ftm2v * minv * fhist2[i][k]);
      scratch[i][k] = c_end * (an + ds) - c_start * (an - ds);
      const double vk = vhalf[i][k] - jump[i][k];
      local[0] += m * vk * scratch[i][k];
      local[1] += m * vk * vk;
      local[2 + k] += m * vk;
    }
    local[5] += m;
  };
  set.each(atom->mask, atom->nlocal, deficit);
  double sum[6];
  MPI_Allreduce(local, sum, 6, MPI_DOUBLE, MPI_SUM, world);
  const double vcm[3] = {sum[2] / sum[5], sum[3] / sum[5], sum[4] / sum[5]};
  const double ww = sum[1] - (sum[2] * sum[2] + sum[3] * sum[3] + sum[4] * sum[4]) / sum[5];
  const double alpha = (ww > 0.0) ? sum[0] / ww : 0.0;

  const auto add = [&](int i) {
    for (int k = 0; k < 3; k++) {
      const double delta = scratch[i][k] - alpha * (vhalf[i][k] - jump[i][k] - vcm[k]);
      jump[i][k] += delta;
      vhalf[i][k] += delta;
    }
  };
  set.each(atom->mask, atom->nlocal, add);
  return true;
}

/* ---------------------------------------------------------------------- */

double **StepControl::next_history()
{
  if (!keeps_history()) return nullptr;
  state.swap(hist1, hist2);
  return state.vec(hist1);
}

/* ---------------------------------------------------------------------- */

void StepControl::step_done(double h)
{
  hlast2 = hlast;
  hlast = h;
}

/* ----------------------------------------------------------------------
   forward rule for the adaptive step: the next jump is predicted as
   [v]^{n+2} ~ 2 h' a' - [v]^{n+1}, a' the quadrature-averaged force of the
   next step extrapolated linearly from this step's and the previous one's
   (a' = a + (h' + h)/(h + h_prev) (a - a_prev), mid-step times), so the
   predicted jump is h' P + h'^2 Q - [v]^{n+1}. Take the largest h' (growing
   by at most ADAPT_GROWTH per step) with (1/8) sum m |[v]^{n+2}|^2 <=
   ADAPT_SAFETY * eps * E, E = max(|pseudo-energy at the start of the
   run|, kinetic energy); if no h' meets it, the h' of the smallest jump.
   Without a previous step (first step of a run) a' = a.
------------------------------------------------------------------------- */

void StepControl::choose_next(const AtomSet &set, double **favg, double **jump)
{
  double **v = atom->v;
  double **fprev = state.vec(hist2);
  const double h = update->dt;
  const bool extrapolate = (hlast2 > 0.0);    // fprev holds the previous step's average
  const double c1 = extrapolate ? h / (h + hlast2) : 0.0;
  const double c2 = extrapolate ? 1.0 / (h + hlast2) : 0.0;

  // sum m of: P.P, P.Q, Q.Q, P.J, Q.J, J.J, v.v
  double local[7] = {0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0};
  const auto moments = [&](int i) {
    const double m = mass_of(i);
    for (int k = 0; k < 3; k++) {
      const double a = force->ftm2v * favg[i][k] / m;
      const double da = extrapolate ? a - force->ftm2v * fprev[i][k] / m : 0.0;
      const double P = 2.0 * (a + c1 * da), Q = 2.0 * c2 * da, J = jump[i][k];
      local[0] += m * P * P;
      local[1] += m * P * Q;
      local[2] += m * Q * Q;
      local[3] += m * P * J;
      local[4] += m * Q * J;
      local[5] += m * J * J;
      local[6] += m * v[i][k] * v[i][k];
    }
  };
  set.each(atom->mask, atom->nlocal, moments);
  double sum[7];
  MPI_Allreduce(local, sum, 7, MPI_DOUBLE, MPI_SUM, world);

  const double mvv2e = force->mvv2e;
  const double scale = MAX(energy_scale, 0.5 * mvv2e * sum[6]);
  const double target = 8.0 * ADAPT_SAFETY * eps * scale / mvv2e;
  const double hcap = MIN(dtmax, ADAPT_GROWTH * h);
  const double hnew = MAX(largest_step(sum, target, hcap, MIN(dtmin, hcap)), dtmin);
  if (hnew != update->dt) set_timestep(hnew);
}

/* ----------------------------------------------------------------------
   the largest step t in [hlow, hcap] whose predicted jump (sums of
   choose_next()) meets the target: a scan down from hcap, then bisection;
   if none does, the t of the smallest jump
------------------------------------------------------------------------- */

double StepControl::largest_step(const double *sum, double target, double hcap, double hlow)
{
  const auto jump8 = [&sum](double t) {    // 8/mvv2e times the predicted jump energy
    return t * t * sum[0] + 2.0 * t * t * t * sum[1] + t * t * t * t * sum[2] - 2.0 * t * sum[3] -
        2.0 * t * t * sum[4] + sum[5];
  };
  double hnew = hcap;
  if (jump8(hcap) > target) {
    const double ratio = pow(hlow / hcap, 1.0 / ADAPT_SAMPLES);
    double above = hcap, best = hcap, best_value = jump8(hcap);
    hnew = -1.0;
    for (int n = 1; (n <= ADAPT_SAMPLES) && (hnew < 0.0); n++) {
      const double t = hcap * pow(ratio, n);
      const double value = jump8(t);
      if (value <= target) {
        // the bound holds at t but not at above: bisect in between
        double good = t;
        for (int iter = 0; iter < ADAPT_BISECT; iter++) {
          const double mid = 0.5 * (good + above);
          if (jump8(mid) <= target)
            good = mid;
          else
            above = mid;
        }
        hnew = good;
      } else {
        if (value < best_value) {
          best = t;
          best_value = value;
        }
        above = t;
      }
    }
    if (hnew < 0.0) hnew = best;    // no step meets the bound: the smallest jump
  }
  return hnew;
}

/* ----------------------------------------------------------------------
   change the time step the way fix dt/reset does
------------------------------------------------------------------------- */

void StepControl::set_timestep(double dt)
{
  update->update_time();
  update->dt = dt;
  update->dt_default = 0;
  if (force->pair) force->pair->reset_dt();
  for (auto &ifix : modify->get_fix_list()) ifix->reset_dt();
  output->reset_dt();
}

/* ---------------------------------------------------------------------- */

void StepControl::save(double *list) const
{
  list[0] = hlast;
  list[1] = hlast2;
}

/* ---------------------------------------------------------------------- */

void StepControl::load(const double *list)
{
  hlast = list[0];
  hlast2 = list[1];
}
