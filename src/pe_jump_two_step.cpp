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

#include "pe_jump_two_step.h"

#include "atom.h"
#include "atom_vec.h"
#include "comm.h"
#include "domain.h"
#include "error.h"
#include "force.h"
#include "input.h"
#include "pe_jump_atom_state.h"
#include "pe_jump_errors.h"
#include "update.h"

#include <algorithm>
#include <cmath>
#include <cstring>

using namespace LAMMPS_NS;
using namespace LAMMPS_NS::PEJump;

/* ---------------------------------------------------------------------- */

TwoStep::TwoStep(LAMMPS *lmp, AtomState &table, bool start_nodes) :
    Pointers(lmp), fresh(0), state(table), cached_step(-1), cached{0.0, 0.0}, at_end(),
    minimized(false), pending_setup(false), reinitialized(false)
{
  at_end.atoms = -1;    // no run yet
  jump_field = state.add("jump", 3, 0.0);
  vsig_field = state.add("vsig", 1, 0.0);
  fstart_field = start_nodes ? state.add("fstart", 3, std::nan("")) : -1;
}

/* ---------------------------------------------------------------------- */

double **TwoStep::jump() const
{
  return state.vec(jump_field);
}

/* ---------------------------------------------------------------------- */

double *TwoStep::vsig() const
{
  return state.val(vsig_field);
}

/* ---------------------------------------------------------------------- */

double **TwoStep::fstart() const
{
  return (fstart_field >= 0) ? state.vec(fstart_field) : nullptr;
}

/* ---------------------------------------------------------------------- */

void TwoStep::init(const char *style)
{
  reinitialized = pending_setup;    // a command between runs initialized LAMMPS
  if (utils::strmatch(update->integrate_style, "^respa"))
    error->all(FLERR, "Fix {} does not support run_style respa: use run_style verlet{}", style,
               errorurl(7));
  // the jump relation needs a step that goes forward: with h = 0 it flips
  // the jump every step, and a change of sign excites the parasitic mode
  if (!(update->dt > 0.0))
    error->all(FLERR,
               "Fix {} needs a timestep > 0, got {}: to run backwards in time, reverse the "
               "velocities instead{}",
               style, update->dt, errorurl(8));
  if (atom->torque_flag)
    error->all(FLERR, "Fix {} integrates point particles only; atom style {} has torques{}", style,
               atom->atom_style, errorurl(12));
  // (the force evaluations of the fixes clear atom->f only, not the extra
  // per-atom forces that such styles clear in Verlet::force_clear)
  if (atom->avec->forceclearflag)
    error->all(FLERR, "Fix {} does not integrate the extra per-atom quantities of atom style {}{}",
               style, atom->atom_style, errorurl(13));

  // a division per atom costs more than the rest of the update
  inverse_mass.assign(atom->ntypes + 1, 0.0);
  if (atom->mass)
    for (int t = 1; t <= atom->ntypes; t++)
      if (atom->mass[t] > 0.0) inverse_mass[t] = 1.0 / atom->mass[t];
}

/* ---------------------------------------------------------------------- */

double TwoStep::inverse_mass_of(int i) const
{
  return atom->rmass ? 1.0 / atom->rmass[i] : inverse_mass[atom->type[i]];
}

/* ----------------------------------------------------------------------
   restart data that does not fit the fix clears started only on the ranks
   that own atoms: every rank must take the same decision
------------------------------------------------------------------------- */

void TwoStep::agree_on_started(const AtomSet &set, const char *style, bool new_step_restarts,
                               const NodeSampler::Tallied &now)
{
  int all_started = 0;
  MPI_Allreduce(&started, &all_started, 1, MPI_INT, MPI_MIN, world);
  if (reading_snapshots()) all_started = 0;
  if ((all_started < 0) && (comm->me == 0))
    utils::logmesg(lmp,
                   "Fix {}: the per-atom state in the restart file does not fit this fix "
                   "(written with other settings or by another version): the two-step scheme "
                   "restarts from the current state\n",
                   style);
  const std::string why = changed_since_run(census(set, now), new_step_restarts);
  if ((all_started > 0) && !why.empty()) {
    all_started = 0;
    if (comm->me == 0)
      utils::logmesg(lmp,
                     "Fix {}: {}: the two-step scheme restarts from the current positions and "
                     "velocities\n",
                     style, why);
  }
  at_end.atoms = -1;
  minimized = false;
  pending_setup = reinitialized = false;

  // velocities that are not finite (a velocity command gone wrong, e.g.
  // velocity scale to a negative temperature) would only show up later
  double **v = atom->v;
  bigint bad = 0, all_bad = 0;
  set.each(atom->mask, atom->nlocal, [&](int i) {
    if (!(std::isfinite(v[i][0]) && std::isfinite(v[i][1]) && std::isfinite(v[i][2]))) ++bad;
  });
  MPI_Allreduce(&bad, &all_bad, 1, MPI_LMP_BIGINT, MPI_SUM, world);
  if (all_bad)
    error->all(FLERR,
               "Fix {}: {} atoms have velocities that are not finite at the start of the run{}",
               style, all_bad, errorurl(9));
  // forces that are not finite (atoms on top of each other) would make
  // the jumps so, and the first step's checks would blame the time step
  double **f = atom->f;
  bad = 0;
  set.each(atom->mask, atom->nlocal, [&](int i) {
    if (!(std::isfinite(f[i][0]) && std::isfinite(f[i][1]) && std::isfinite(f[i][2]))) ++bad;
  });
  MPI_Allreduce(&bad, &all_bad, 1, MPI_LMP_BIGINT, MPI_SUM, world);
  if (all_bad)
    error->all(FLERR, "Fix {}: {} atoms have forces that are not finite at the start of the run{}",
               style, all_bad, errorurl(10));
  started = (all_started > 0) ? 1 : 0;
}

/* ----------------------------------------------------------------------
   the snapshots of a rerun are unrelated states: the log would say at
   each that the velocities changed (and the restart of a new start
   inside a coarse step of pe_jump/async would hand stale impulses to the
   velocities read)
------------------------------------------------------------------------- */

bool TwoStep::reading_snapshots() const
{
  return input->command && (strcmp(input->command, "rerun") == 0);
}

/* ---------------------------------------------------------------------- */

void TwoStep::start(const AtomSet &set, double **f, double scale,
                    const std::function<double(int)> &step)
{
  double **jmp = jump();
  set.each(atom->mask, atom->nlocal, [&](int i) {
    const double m = atom->rmass ? atom->rmass[i] : atom->mass[atom->type[i]];
    const double dtfm = scale * force->ftm2v * step(i) / m;
    for (int k = 0; k < 3; k++) jmp[i][k] = dtfm * f[i][k];
    mark(i);
  });
  forget_energies();
}

/* ---------------------------------------------------------------------- */

void TwoStep::open(const AtomSet &set, bool fingerprint) const
{
  double **v = atom->v;
  double **jmp = jump();
  double *sig = fingerprint ? vsig() : nullptr;
  set.each(atom->mask, atom->nlocal, [&](int i) {
    for (int k = 0; k < 3; k++) v[i][k] += 0.5 * jmp[i][k];
    if (sig) sig[i] = velocity_fingerprint(v[i]);
  });
}

/* ---------------------------------------------------------------------- */

void TwoStep::jump_loop(const AtomSet &set, double **favg, const Loop &step, double *mag,
                        const ParasiticDamping::Step *damp) const
{
  // the options are fixed for the whole loop: one instance each, so that
  // the inner loop carries no tests (it is the fine steps' per-atom cost)
  const bool ahead = step.ahead >= 0.0;
  const int which = (ahead ? 1 : 0) + (step.fingerprint ? 2 : 0) + (damp ? 4 : 0);
  switch (which) {
    case 0:
      return jump_loop_as<false, false, false>(set, favg, step, mag, damp);
    case 1:
      return jump_loop_as<true, false, false>(set, favg, step, mag, damp);
    case 2:
      return jump_loop_as<false, true, false>(set, favg, step, mag, damp);
    case 3:
      return jump_loop_as<true, true, false>(set, favg, step, mag, damp);
    case 4:
      return jump_loop_as<false, false, true>(set, favg, step, mag, damp);
    case 5:
      return jump_loop_as<true, false, true>(set, favg, step, mag, damp);
    case 6:
      return jump_loop_as<false, true, true>(set, favg, step, mag, damp);
    default:
      return jump_loop_as<true, true, true>(set, favg, step, mag, damp);
  }
}

/* ----------------------------------------------------------------------
   AHEAD: the next step begins (step.ahead >= 0), SIGN: fingerprints,
   DAMP: the jumps are damped (damp)
------------------------------------------------------------------------- */

template <bool AHEAD, bool SIGN, bool DAMP>
void TwoStep::jump_loop_as(const AtomSet &set, double **favg, const Loop &step, double *mag,
                           const ParasiticDamping::Step *damp) const
{
  double *x = flat(atom->x);
  double *v = flat(atom->v);
  double *jmp_all = flat(jump());
  const double *fav = flat(favg);
  double *sig = (SIGN && step.fingerprint) ? vsig() : nullptr;
  const bool ahead = !AHEAD || (step.ahead >= 0.0);
  const double *rmass = atom->rmass;
  const double *minv = inverse_mass.data();
  const int *type = atom->type;
  const double kick = 2.0 * step.h * force->ftm2v;
  const double rest = step.rest, dt_ahead = step.ahead;
  // (a Lobatto rule's primary node is the step end: nothing to move then)
  const bool moves = (rest != 0.0) || (AHEAD && ahead);
  double vv = mag[0], jj = mag[1];
  set.each(atom->mask, atom->nlocal, [&](int i) {
    const double dtfm = kick * (rmass ? 1.0 / rmass[i] : minv[type[i]]);
    double *xi = x + 3 * i, *vi = v + 3 * i, *ji = jmp_all + 3 * i;
    const double *fi = fav + 3 * i;
    double vh[3] = {vi[0], vi[1], vi[2]};
    double jmp[3] = {ji[0], ji[1], ji[2]};
    double xn[3], vnew[3];
    for (int k = 0; k < 3; k++) {
      xn[k] = xi[k] + rest * vh[k];
      const double d = dtfm * fi[k];
      if (DAMP) damp->pull(i, k, dtfm, fi[k], d, jmp[k]);
      vnew[k] = jump_component(d, vh[k], jmp[k]);
      if (AHEAD && ahead) {
        vh[k] += 0.5 * jmp[k];
        xn[k] += dt_ahead * vh[k];
      }
    }
    for (int k = 0; k < 3; k++) {
      if (moves) xi[k] = xn[k];
      vi[k] = vh[k];
      ji[k] = jmp[k];
    }
    // (no fingerprint when a step begins ahead: nothing may change v then)
    if (SIGN && sig) sig[i] = velocity_fingerprint(vi);
    vv = MAX(vv, vnew[0] * vnew[0] + vnew[1] * vnew[1] + vnew[2] * vnew[2]);
    jj = MAX(jj, jmp[0] * jmp[0] + jmp[1] * jmp[1] + jmp[2] * jmp[2]);
  });
  mag[0] = vv;
  mag[1] = jj;
}

/* ---------------------------------------------------------------------- */

void TwoStep::mark(int i) const
{
  vsig()[i] = velocity_fingerprint(atom->v[i]);
}

/* ---------------------------------------------------------------------- */

void TwoStep::mark_all(const AtomSet &set) const
{
  double **v = atom->v;
  double *sig = vsig();
  set.each(atom->mask, atom->nlocal, [&](int i) {
    sig[i] = velocity_fingerprint(v[i]);
  });
}

/* ---------------------------------------------------------------------- */

void TwoStep::end_run(const AtomSet &set, const NodeSampler::Tallied &energy)
{
  mark_all(set);
  at_end = census(set, energy);
  pending_setup = true;
}

/* ---------------------------------------------------------------------- */

bool TwoStep::check_run_without_setup(const char *style, const AtomSet &set, bool clocks_changed)
{
  pending_setup = false;
  // (the time step may change: the scheme takes any step sequence)
  std::string why = changed_since_run(census(set, {false, 0.0, 0.0}), false);
  if (why.empty() && (velocity_change(set, false) != 0))
    why = "velocities were changed since the last run";
  if (why.empty() && clocks_changed) why = "the atoms on the fine clock changed since the last run";
  if (!why.empty())
    error->all(FLERR,
               "Fix {}: {}, and this run starts with 'pre no': use run with pre yes (the "
               "default){}",
               style, why, errorurl(11));
  const bool stale = reinitialized;
  reinitialized = false;
  return stale;
}

/* ---------------------------------------------------------------------- */

void TwoStep::save_census(double *list) const
{
  const bool between_runs = (update->whichflag == 0) && (at_end.atoms >= 0);
  const Census &c = at_end;
  const double values[NCENSUS] = {between_runs ? static_cast<double>(c.atoms) : -1.0,
                                  c.moment[0],
                                  c.moment[1],
                                  c.moment[2],
                                  c.scale,
                                  c.mass,
                                  c.dt,
                                  c.energy.known ? 1.0 : 0.0,
                                  c.energy.energy,
                                  c.energy.magnitude,
                                  minimized ? 1.0 : 0.0};
  std::copy(values, values + NCENSUS, list);
}

/* ---------------------------------------------------------------------- */

void TwoStep::load_census(const double *list)
{
  at_end = {
      static_cast<bigint>(list[0]),      {list[1], list[2], list[3]}, list[4], list[5], list[6],
      {list[7] != 0.0, list[8], list[9]}};
  minimized = (list[10] != 0.0);
}

/* ---------------------------------------------------------------------- */

TwoStep::Census TwoStep::census(const AtomSet &set, const NodeSampler::Tallied &energy) const
{
  double local[6] = {0.0, 0.0, 0.0, 0.0, 0.0, 0.0}, global[6];
  double **x = atom->x;
  const imageint *image = atom->image;
  const tagint *tag = atom->tag;
  const double *rmass = atom->rmass;
  const double *mass = atom->mass;
  const int *type = atom->type;
  set.each(atom->mask, atom->nlocal, [&](int i) {
    double u[3];
    domain->unmap(x[i], image[i], u);
    const double w = 1.0 + static_cast<double>(id_hash(tag[i]) >> 11) / 9007199254740992.0;
    for (int k = 0; k < 3; k++) local[k] += w * u[k];
    local[3] += w * sqrt(u[0] * u[0] + u[1] * u[1] + u[2] * u[2]);
    local[4] += w * (rmass ? rmass[i] : mass[type[i]]);
    local[5] += 1.0;
  });
  MPI_Allreduce(local, global, 6, MPI_DOUBLE, MPI_SUM, world);
  return {static_cast<bigint>(global[5]),
          {global[0], global[1], global[2]},
          global[3],
          global[4],
          update->dt,
          energy};
}

/* ----------------------------------------------------------------------
   why the state of the last run no longer fits ("" if it does)
------------------------------------------------------------------------- */

std::string TwoStep::changed_since_run(const Census &now, bool new_step_restarts) const
{
  if (minimized) return "the atoms were moved by an energy minimization since the last run";
  if (at_end.atoms < 0) return "";
  // (the counts only: atoms deleted and created in between, or moved out
  // of and into the group, are not told apart)
  if (now.atoms != at_end.atoms)
    return fmt::format("the group had {} atoms at the end of the last run and has {} now (atoms "
                       "deleted, created, or moved out of or into it)",
                       at_end.atoms, now.atoms);
  // wrapping into a periodic box changes a position by round-off only
  const double tolerance = 1e-12 * std::max(now.scale, at_end.scale);
  for (int k = 0; k < 3; k++)
    if (std::fabs(now.moment[k] - at_end.moment[k]) > tolerance)
      return "atoms of the group were moved (or renumbered) since the last run (displace_atoms, "
             "set, change_box with remap, reset_atoms id, ...)";
  if (std::fabs(now.mass - at_end.mass) > 1e-12 * std::max(now.mass, at_end.mass))
    return "the masses of atoms of the group changed since the last run";
  // the same energy summed in another order (new lists) differs by round-off
  const auto &e0 = at_end.energy, &e1 = now.energy;
  if (e0.known && e1.known &&
      (std::fabs(e1.energy - e0.energy) > 1e-10 * std::max(e0.magnitude, e1.magnitude)))
    return fmt::format("the potential energy at the current positions changed since the last run "
                       "(from {} to {}: pair_style, pair_coeff, bond_coeff, special_bonds, "
                       "kspace_style, set type or charge, a box changed without moving the atoms, "
                       "...)",
                       e0.energy, e1.energy);
  if (new_step_restarts && (now.dt != at_end.dt))
    return fmt::format("the time step changed since the last run (from {} to {}; give "
                       "compensate no (or yes) to carry the jumps over instead)",
                       at_end.dt, now.dt);
  return "";
}

/* ---------------------------------------------------------------------- */

bool TwoStep::any_changed(const AtomSet &set) const
{
  double **v = atom->v;
  const double *sig = vsig();
  bool any = false;
  set.each(atom->mask, atom->nlocal, [&](int i) {
    if (velocity_fingerprint(v[i]) != sig[i]) any = true;
  });
  return any;
}

/* ----------------------------------------------------------------------
   a reversal of all velocities: the free-flight velocity -v^n + [v]^n/2 =
   -v^{n-1/2} continues backwards in time with the same jump
------------------------------------------------------------------------- */

int TwoStep::velocity_change(const AtomSet &set, bool can_reverse)
{
  double **v = atom->v;
  const double *sig = vsig();
  int local[2] = {0, 0};    // some differ, some are not reversed
  set.each(atom->mask, atom->nlocal, [&](int i) {
    const double back[3] = {-v[i][0], -v[i][1], -v[i][2]};
    if (velocity_fingerprint(v[i]) != sig[i]) local[0] = 1;
    if (velocity_fingerprint(back) != sig[i]) local[1] = 1;
  });
  int global[2];
  MPI_Allreduce(local, global, 2, MPI_INT, MPI_MAX, world);
  if (!global[0]) return 0;
  if (global[1] || !can_reverse) return 2;
  mark_all(set);
  forget_energies();
  return 1;
}

/* ---------------------------------------------------------------------- */

const double *TwoStep::energies(const AtomSet &set)
{
  if (cached_step == update->ntimestep) return cached;
  energies_now(set, cached);
  cached_step = update->ntimestep;
  return cached;
}

/* ---------------------------------------------------------------------- */

void TwoStep::energies_now(const AtomSet &set, double *e) const
{
  double **v = atom->v;
  double **jmp = jump();
  double local[2] = {0.0, 0.0};
  set.each(atom->mask, atom->nlocal, [&](int i) {
    const double m = atom->rmass ? atom->rmass[i] : atom->mass[atom->type[i]];
    // with v^{n+1/2} = v^n + [v]^n/2: v^{n-1/2}.v^{n+1/2} = |v^n|^2 - |[v]^n|^2/4
    for (int k = 0; k < 3; k++) {
      local[0] += m * (v[i][k] * v[i][k] - 0.25 * jmp[i][k] * jmp[i][k]);
      local[1] += m * jmp[i][k] * jmp[i][k];
    }
  });
  MPI_Allreduce(local, e, 2, MPI_DOUBLE, MPI_SUM, world);
  e[0] *= 0.5 * force->mvv2e;
  e[1] *= 0.125 * force->mvv2e;
}
