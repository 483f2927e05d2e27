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

#include "pe_jump_stability_guard.h"

#include "atom.h"
#include "domain.h"
#include "error.h"
#include "fix.h"
#include "modify.h"
#include "neighbor.h"
#include "output.h"
#include "pe_jump_errors.h"
#include "pe_jump_parasitic_damping.h"
#include "pe_jump_quadrature.h"
#include "update.h"

#include <cfloat>
#include <cmath>

using namespace LAMMPS_NS;
using namespace LAMMPS_NS::PEJump;

static constexpr double STOP_GROWTH = 1.0e6;    // jump growth that is always instability
static constexpr double HINT_GROWTH = 2.0;      // ... that is instability if atoms move far
static constexpr int HINT_STEPS = 10;           // ... in this many steps in a row
// jumps grown STOP_GROWTH-fold whose energy is below this share of the
// kinetic energy grew with the motion (from a start at rest), not by
// instability: they become the reference
static constexpr double MOTION_SHARE = 1.0e-3;
// margins of the bounds on the excursion (ReachBound): relative, on the
// largest speed and on half the skin, and on each update of a coordinate
static constexpr double SPEED_MARGIN = 1.0e-9;
static constexpr double REACH_MARGIN = 1.0e-9;
static constexpr double POSITION_ROUNDING = DBL_EPSILON;

/* ---------------------------------------------------------------------- */

StabilityGuard::StabilityGuard(LAMMPS *lmp) :
    Pointers(lmp), stats{0.0, 0.0}, slow{0.0, 0.0}, valid(false), jump_ref(0.0), last_growth(0.0),
    hinted(0), trusted(false)
{
}

/* ---------------------------------------------------------------------- */

void StabilityGuard::start_run(bool free_flight_only)
{
  trusted = free_flight_only;
  valid = false;
  reach.forget();
  jump_ref = 0.0;
  hinted = 0;
}

/* ---------------------------------------------------------------------- */

void StabilityGuard::set_stats(double vv, double jj)
{
  stats[0] = std::isfinite(vv) ? vv : BLOWUP;
  stats[1] = std::isfinite(jj) ? jj : BLOWUP;
  valid = true;
}

/* ---------------------------------------------------------------------- */

void StabilityGuard::set_slow_stats(double vv, double jj)
{
  slow[0] = std::isfinite(vv) ? vv : BLOWUP;
  slow[1] = std::isfinite(jj) ? jj : BLOWUP;
}

/* ---------------------------------------------------------------------- */

void StabilityGuard::step_measures(const AtomSet &set, const FreeFlight &vel, double **jump,
                                   double **xhold, const Nodes &at, double *local)
{
  if (!has_stats()) {
    measure(set, vel, jump, xhold, at, local);
    return;
  }
  measures_from_stats(at.h, local);
  if (xhold)
    local[0] = excursion_since(set, vel, xhold, at.lo, at.hi);
  else
    forget_reach();
}

/* ---------------------------------------------------------------------- */

void StabilityGuard::measures_from_stats(double h, double *local) const
{
  local[1] = h * h * stats[0];
  local[2] = h * h * stats[1];
  local[3] = stats[1];
  local[4] = stats[0];
}

/* ---------------------------------------------------------------------- */

void StabilityGuard::join_slow_stats(double coarse, double *local) const
{
  local[1] = MAX(local[1], coarse * coarse * slow[0]);
  local[2] = MAX(local[2], coarse * coarse * slow[1]);
  local[3] = MAX(local[3], slow[1]);
  local[4] = MAX(local[4], slow[0]);
}

/* ---------------------------------------------------------------------- */

void StabilityGuard::measure(const AtomSet &set, const FreeFlight &vel, double **jump,
                             double **xhold, const Nodes &at, double *local) const
{
  double **x = atom->x;
  set.each(atom->mask, atom->nlocal, [&](int i) {
    const double vhalf[3] = {vel(i, 0), vel(i, 1), vel(i, 2)};
    measure_one(x[i], xhold ? xhold[i] : nullptr, vhalf, jump[i], at, local);
  });
}

/* ----------------------------------------------------------------------
   Lobatto rules: the nodes lie between q^n and q^{n+1} (the primary node),
   whose distances from the last build LAMMPS checks if it checks every
   step; the largest distance of x + t v over t in [0, h] is at one of the
   ends, and after a build at q^{n+1} the nodes are within one step length
   (bounded by the guard) of it
------------------------------------------------------------------------- */

bool StabilityGuard::ends_checked(const Quadrature &rule, double lo, double hi, double h) const
{
  return rule.has_end_nodes() && (neighbor->every == 1) && (neighbor->delay == 0) && (lo >= 0.0) &&
      (hi <= h);
}

/* ---------------------------------------------------------------------- */

double StabilityGuard::excursion(const AtomSet &set, const FreeFlight &vel, double **xhold,
                                 double lo, double hi) const
{
  const double *x = flat(atom->x);
  const double *x0 = flat(xhold);
  double worst = 0.0;
  const auto one = [&](int i) {
    const double vhalf[3] = {vel(i, 0), vel(i, 1), vel(i, 2)};
    double dlo = 0.0, dhi = 0.0;
    for (int k = 0; k < 3; k++) {
      const double a = x[3 * i + k] - x0[3 * i + k];
      dlo += (a + lo * vhalf[k]) * (a + lo * vhalf[k]);
      dhi += (a + hi * vhalf[k]) * (a + hi * vhalf[k]);
    }
    worst = MAX(worst, MAX(dlo, dhi));
  };
  set.each(atom->mask, atom->nlocal, one);
  return worst;
}

/* ----------------------------------------------------------------------
   the farthest an atom moves in time t at speeds up to sqrt(speed2), with
   margins for rounding: of the speeds, and of the positions at each of at
   most moves updates (half an ulp of the largest coordinate, which is
   within the box bounds and a skin)
------------------------------------------------------------------------- */

double StabilityGuard::travel(double t, double speed2, int moves) const
{
  // (LAMMPS sets the bounding box of a tilted box only)
  const double *lo = domain->triclinic ? domain->boxlo_bound : domain->boxlo;
  const double *hi = domain->triclinic ? domain->boxhi_bound : domain->boxhi;
  double extent = 0.0;
  for (int k = 0; k < 3; k++) extent = MAX(extent, MAX(fabs(lo[k]), fabs(hi[k])));
  extent += neighbor->skin;
  return t * sqrt(speed2) * (1.0 + SPEED_MARGIN) + moves * POSITION_ROUNDING * extent;
}

/* ----------------------------------------------------------------------
   the distance below which the verdict of a measure is known (half the
   skin, with a margin for the rounding of the measure)
------------------------------------------------------------------------- */

double StabilityGuard::clear() const
{
  return (1.0 - REACH_MARGIN) * 0.5 * neighbor->skin;
}

/* ----------------------------------------------------------------------
   a step moves the atoms at most three times: to the primary node, on to
   the end, and ahead into the next step
------------------------------------------------------------------------- */

void StabilityGuard::step(double h)
{
  reach.moved(travel(h, MAX(stats[0], slow[0]), 3));
}

/* ----------------------------------------------------------------------
   after a measure the bound covers the rest of the step (at most h)
------------------------------------------------------------------------- */

double StabilityGuard::excursion_since(const AtomSet &set, const FreeFlight &vel, double **xhold,
                                       double lo, double hi)
{
  if (free_flight_only() && reach.within(clear(), neighbor->ncalls)) return 0.0;
  const double worst = excursion(set, vel, xhold, lo, hi);
  if (free_flight_only())
    reach.measured(sqrt(worst) + travel(update->dt, MAX(stats[0], slow[0]), 3), neighbor->ncalls);
  else
    reach.forget();
  return worst;
}

/* ---------------------------------------------------------------------- */

bool StabilityGuard::rebuild_forced() const
{
  if (neighbor->dist_check || neighbor->build_once) return false;
  const bigint now = update->ntimestep;
  if (output->restart_flag && (now == output->next_restart)) return true;
  for (const auto *ifix : modify->get_fix_list())
    if (ifix->force_reneighbor && (now == ifix->next_reneighbor)) return true;
  const int ago = neighbor->ago + 1;
  return (ago >= neighbor->delay) && (ago % neighbor->every == 0);
}

/* ----------------------------------------------------------------------
   with skin 0 the lists hold the pairs within the cutoff at the positions
   of the last build only: every force evaluation elsewhere (quadrature
   nodes, the step end for energy output, slow atoms at coarse nodes)
   misses the pairs that came within the cutoff since, and the guard has no
   distance to check against
------------------------------------------------------------------------- */

void StabilityGuard::refuse_zero_skin(const char *style, bool evaluations_at_builds,
                                      const std::string &what) const
{
  if ((neighbor->skin > 0.0) || evaluations_at_builds) return;
  error->all(FLERR,
             "Fix {} needs a neighbor skin > 0 (neighbor {} ...): {} evaluates forces away from "
             "where the lists are built{}",
             style, neighbor->skin, what, errorurl(4));
}

/* ----------------------------------------------------------------------
   the scheme is unstable if the jumps have grown by more than STOP_GROWTH
   since the first steps of the run (the first step where anything moves),
   or by more than HINT_GROWTH while moving atoms (or their jumps) by more
   than half the skin in HINT_STEPS steps in a row, or with steps beyond
   half the skin: a hard collision that a step samples at its peak makes
   a jump that moves an atom far for a step or two, an unstable scheme
   keeps it; a large step that is stable only needs a larger skin.
   Otherwise a rebuild is due where the nodes leave half the skin.
------------------------------------------------------------------------- */

StabilityGuard::Verdict StabilityGuard::judge(const double *global)
{
  if (jump_ref == 0.0) {
    // a run that starts at rest (a perfect lattice at T = 0 that a
    // thermostat heats) has jumps of round-off size at first: jumps that
    // move an atom by less than a millionth of the skin per step are no
    // reference (h^2 = global[2] / global[3])
    const double skin2 = neighbor->skin * neighbor->skin;
    const double rest = (global[2] > 0.0) ? 1.0e-12 * skin2 * global[3] / global[2] : 0.0;
    jump_ref = MAX(MAX(global[3], global[4]), rest);
  }
  last_growth = (jump_ref > 0.0) ? sqrt(global[3] / jump_ref) : 0.0;

  const double half_skin = 0.5 * neighbor->skin;
  const double limit = (half_skin > 0.0) ? half_skin * half_skin : BLOWUP;
  const bool large = (global[1] >= limit) || (global[2] >= limit);
  hinted = (large && (last_growth >= HINT_GROWTH)) ? hinted + 1 : 0;
  const bool too_far = (global[1] >= limit);
  if ((last_growth >= STOP_GROWTH) || (hinted >= HINT_STEPS) || (hinted && too_far))
    return UNSTABLE;
  if (too_far) return TOO_FAR;
  if (global[0] > limit) return REBUILD;
  return FINE;
}

/* ---------------------------------------------------------------------- */

bool StabilityGuard::conclude(const char *style, const double *local, ParasiticDamping &damping,
                              const std::function<const double *()> &energies,
                              const std::function<std::string()> &advice)
{
  double values[NMEASURES + 1], global[NMEASURES + 1];
  for (int k = 0; k < NMEASURES; k++) values[k] = local[k];
  values[NMEASURES] = damping.take_impulse();
  MPI_Allreduce(values, global, NMEASURES + 1, MPI_DOUBLE, MPI_MAX, world);
  if (damping.impulse_anywhere(global[NMEASURES] > 0.0)) damping.note(lmp, style, true);

  Verdict verdict = judge(global);
  if ((verdict == UNSTABLE) && (growth() >= STOP_GROWTH)) {
    // a run that starts at rest and is then loaded (an indenter, an
    // impact) has jumps that grow with the forces by any factor: unstable
    // only if the jumps carry a share of the kinetic energy
    const double *e = energies();
    const double kinetic = e[0] + e[1];    // e[0] = kinetic - jump energy
    if (e[1] < MOTION_SHARE * kinetic) {
      jump_ref = global[3];
      verdict = judge(global);
    }
  }
  switch (verdict) {
    case UNSTABLE:
      error->all(FLERR,
                 "Fix {} is unstable at step {}: the momentum jumps grew {:.3g}-fold since the "
                 "start of the run (jump energy {:.8g}). {}",
                 style, update->ntimestep, growth(), energies()[1], advice());
      break;
    case TOO_FAR:
      error->all(FLERR,
                 "Fix {}: atoms move more than half the neighbor skin ({}) between the force "
                 "evaluations of step {}{}",
                 style, neighbor->skin, update->ntimestep, errorurl(3));
      break;
    case REBUILD:
      return true;
    case FINE:
      break;
  }
  return false;
}
