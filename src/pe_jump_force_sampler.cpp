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

#include "pe_jump_force_sampler.h"

#include "angle.h"
#include "atom.h"
#include "bond.h"
#include "comm.h"
#include "dihedral.h"
#include "error.h"
#include "fix.h"
#include "force.h"
#include "improper.h"
#include "kspace.h"
#include "lammps.h"
#include "modify.h"
#include "neigh_list.h"
#include "neighbor.h"
#include "pair.h"
#include "pe_jump_atom_set.h"
#include "pe_jump_errors.h"
#include "pe_jump_moving_ghosts.h"
#include "timer.h"
#include "utils.h"

#include <cmath>
#include <cstring>

// with the OPENMP package, /omp styles leave the forces of the threads
// unreduced unless they are the last /omp style of the Verlet order
// (LMP_OPENMP: LAMMPS' build defines it when the package is installed)
#if defined(LMP_OPENMP)
#include "fix_omp.h"
#include "thr_data.h"
#endif

using namespace LAMMPS_NS;
using namespace LAMMPS_NS::PEJump;

/* ---------------------------------------------------------------------- */

ForceSampler::ForceSampler(LAMMPS *lmp) :
    Pointers(lmp), touched(nullptr), omp(nullptr), counted_at(-1)
{
  for (double &c : count) c = 0.0;
}

/* ---------------------------------------------------------------------- */

int ForceSampler::parse(const char *name)
{
  if (strcmp(name, "pair") == 0) return PAIR;
  if (strcmp(name, "bond") == 0) return BOND;
  if (strcmp(name, "angle") == 0) return ANGLE;
  if (strcmp(name, "dihedral") == 0) return DIHEDRAL;
  if (strcmp(name, "improper") == 0) return IMPROPER;
  if (strcmp(name, "kspace") == 0) return KSPACE;
  if (strcmp(name, "all") == 0) return ALL;
  return 0;
}

/* ----------------------------------------------------------------------
   measured with bond_style bpm/spring and damping 1, 0.1, 0.02: midpoint
   and lobatto 3 grow unstable at any time step, lobatto 2 follows fix nve
------------------------------------------------------------------------- */

void ForceSampler::refuse_velocity_forces(const char *style, const std::string &rule,
                                          bool end_nodes) const
{
  if (!comm->ghost_velocity || end_nodes) return;
  error->all(FLERR,
             "Fix {} with quadrature {}: comm_modify vel yes is set (forces that depend on "
             "velocities grow the jumps){}",
             style, rule, errorurl(31));
}

/* ----------------------------------------------------------------------
   peridynamic pair styles advance per-bond state at every evaluation:
   damage (broken bonds, the critical stretch), and with peri/ves and
   peri/eps the viscoelastic and plastic history by a whole time step.
   Only a rule that evaluates once per step, at the step end, keeps it
------------------------------------------------------------------------- */

void ForceSampler::refuse_stateful_forces(const char *style, const std::string &rule,
                                          bool end_nodes) const
{
  if (!atom->peri_flag || end_nodes) return;
  error->all(FLERR,
             "Fix {} with quadrature {}: pair style {} advances the state of its bonds at every "
             "force evaluation{}",
             style, rule, force->pair_style, errorurl(32));
}

/* ----------------------------------------------------------------------
   the packages by the style of the fix that their package command makes
   (KOKKOS: by its instance, which -k on makes)
------------------------------------------------------------------------- */

void ForceSampler::refuse_accelerators(const char *style) const
{
  static constexpr const char *PACKAGE_FIXES[] = {"GPU", "INTEL"};
  std::string package;
  if (lmp->kokkos) package = "KOKKOS";
  for (const char *name : PACKAGE_FIXES)
    if (!modify->get_fix_by_style(fmt::format("^{}$", name)).empty()) package = name;
  if (!package.empty())
    error->all(FLERR, "Fix {} does not support the {} package{}", style, package, errorurl(67));
}

/* ---------------------------------------------------------------------- */

int ForceSampler::present() const
{
  int mask = 0;
  if (force->pair && force->pair->compute_flag) mask |= PAIR;
  if (atom->molecular != Atom::ATOMIC) {
    if (force->bond) mask |= BOND;
    if (force->angle) mask |= ANGLE;
    if (force->dihedral) mask |= DIHEDRAL;
    if (force->improper) mask |= IMPROPER;
  }
  if (force->kspace && force->kspace->compute_flag) mask |= KSPACE;
  return mask;
}

/* ---------------------------------------------------------------------- */

void ForceSampler::set_hooks(const std::vector<Fix *> &prepare, const std::vector<Fix *> &project)
{
  preparations = prepare;
  projections = project;
  omp = nullptr;
  for (auto *fix : preparations)
    if (utils::strmatch(fix->style, "^OMP$")) omp = fix;
#if !defined(LMP_OPENMP)
  if (omp && (comm->nthreads > 1))
    error->all(FLERR,
               "PE-JUMP was built without the OPENMP package and cannot reduce the forces of "
               "several OpenMP threads{}",
               errorurl(15));
#endif
}

/* ---------------------------------------------------------------------- */

void ForceSampler::compute(int mask, int eflag, int vflag)
{
  timer->stamp(Timer::MODIFY);
  if (touched && touched->ghosts)
    touched->ghosts->forward();
  else
    comm->forward_comm();
  timer->stamp(Timer::COMM);

  clear_forces();
  for (auto *fix : preparations) fix->pre_force(vflag);
  timer->stamp(Timer::MODIFY);

  mask &= present();
  if (mask & PAIR) {
    force->pair->compute(eflag, vflag);
    timer->stamp(Timer::PAIR);
  }
  if (mask & (BOND | ANGLE | DIHEDRAL | IMPROPER)) {
    if (mask & BOND) force->bond->compute(eflag, vflag);
    if (mask & ANGLE) force->angle->compute(eflag, vflag);
    if (mask & DIHEDRAL) force->dihedral->compute(eflag, vflag);
    if (mask & IMPROPER) force->improper->compute(eflag, vflag);
    timer->stamp(Timer::BOND);
  }
  if (mask & KSPACE) {
    // an evaluation that tallies nothing leaves the tallies of the last
    // one (ewald/disp and pppm/disp zero their energy, and ewald/disp its
    // virial, at every call)
    KSpace *kspace = force->kspace;
    const double energy = kspace->energy;
    double virial[6];
    for (int k = 0; k < 6; k++) virial[k] = kspace->virial[k];
    kspace->compute(eflag, vflag);
    if (!eflag) kspace->energy = energy;
    if (!vflag)
      for (int k = 0; k < 6; k++) kspace->virial[k] = virial[k];
    timer->stamp(Timer::KSPACE);
  }
  reduce_threads();

  if (force->newton) {
    if (touched && touched->ghosts)
      touched->ghosts->reverse();
    else
      comm->reverse_comm();
    timer->stamp(Timer::COMM);
  }
  project();
}

/* ----------------------------------------------------------------------
   the forces of the owned atoms (all, or those touched) and, with newton
   on, of the ghosts
------------------------------------------------------------------------- */

void ForceSampler::clear_forces()
{
  double **f = atom->f;
  if (!touched) {
    size_t nbytes = sizeof(double) * atom->nlocal;
    if (force->newton) nbytes += sizeof(double) * atom->nghost;
    if (nbytes) memset(&f[0][0], 0, 3 * nbytes);
    return;
  }
  if (touched->nfirst > 0) memset(&f[0][0], 0, 3 * sizeof(double) * touched->nfirst);
  double *fflat = flat(f);
  for (const int i : *touched->after) fflat[3 * i] = fflat[3 * i + 1] = fflat[3 * i + 2] = 0.0;
  if (!force->newton || (atom->nghost == 0)) return;
  // (the ghosts whose forces go back to their owners)
  if (touched->ghosts)
    touched->ghosts->clear_forces();
  else
    memset(&f[atom->nlocal][0], 0, 3 * sizeof(double) * atom->nghost);
}

/* ----------------------------------------------------------------------
   /omp styles add the forces of threads other than the first into their
   own arrays, which the last /omp style of the Verlet order reduces. If
   that style was not among the contributions computed, reduce here.
------------------------------------------------------------------------- */

void ForceSampler::reduce_threads()
{
#if defined(LMP_OPENMP)
  auto *fix = static_cast<FixOMP *>(omp);
  if (!fix || fix->get_reduced() || (fix->get_nthr() < 2)) return;
  double **f = atom->f;
  const int nall = atom->nlocal + atom->nghost;
  for (int t = 1; t < fix->get_nthr(); t++) {
    double **ft = fix->get_thr(t)->get_f();
    for (int i = 0; i < nall; i++)
      for (int k = 0; k < 3; k++) f[i][k] += ft[i][k];
  }
#endif
}

/* ---------------------------------------------------------------------- */

void ForceSampler::project()
{
  for (auto *fix : projections) fix->post_force(0);
}

/* ---------------------------------------------------------------------- */

double ForceSampler::energy(int mask, double *magnitude) const
{
  mask &= present();
  double part[6] = {0.0, 0.0, 0.0, 0.0, 0.0, 0.0};
  if (mask & PAIR) {
    part[0] = force->pair->eng_vdwl;
    part[1] = force->pair->eng_coul;
  }
  if (mask & BOND) part[2] = force->bond->energy;
  if (mask & ANGLE) part[3] = force->angle->energy;
  if (mask & DIHEDRAL) part[4] = force->dihedral->energy;
  if (mask & IMPROPER) part[5] = force->improper->energy;
  double one[2] = {0.0, 0.0}, all[2];
  for (const double e : part) {
    one[0] += e;
    one[1] += std::fabs(e);
  }
  MPI_Allreduce(one, all, 2, MPI_DOUBLE, MPI_SUM, world);
  if (mask & KSPACE) {    // already summed over ranks
    all[0] += force->kspace->energy;
    all[1] += std::fabs(force->kspace->energy);
  }
  if (magnitude) *magnitude = all[1];
  return all[0];
}

/* ---------------------------------------------------------------------- */

double ForceSampler::fraction(int mask)
{
  const int have = present();
  if ((mask & have) == have) return 1.0;
  if (counted_at != neighbor->ncalls) recount();

  double all = 0.0, part = 0.0;
  for (int k = 0; k < NCOUNT; ++k) {
    if (!(have & (1 << k))) continue;
    all += count[k];
    if (mask & (1 << k)) part += count[k];
  }
  return (all > 0.0) ? part / all : 0.0;
}

/* ----------------------------------------------------------------------
   global interaction counts: pairs of the pair style's neighbor list and
   the bonded lists of the neighbor class. k-space has no countable
   interactions and is left out of the fractions.
------------------------------------------------------------------------- */

void ForceSampler::recount()
{
  double local[NCOUNT] = {0.0, 0.0, 0.0, 0.0, 0.0};
  if (force->pair && force->pair->list) {
    const NeighList *list = force->pair->list;
    for (int ii = 0; ii < list->inum; ++ii) local[0] += list->numneigh[list->ilist[ii]];
  }
  // the neighbor class sets the topology list sizes only for styles that exist
  const int have = present();
  if (have & BOND) local[1] = neighbor->nbondlist;
  if (have & ANGLE) local[2] = neighbor->nanglelist;
  if (have & DIHEDRAL) local[3] = neighbor->ndihedrallist;
  if (have & IMPROPER) local[4] = neighbor->nimproperlist;
  MPI_Allreduce(local, count, NCOUNT, MPI_DOUBLE, MPI_SUM, world);
  counted_at = neighbor->ncalls;
}
