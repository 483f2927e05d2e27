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

/* ----------------------------------------------------------------------
   Explicit pseudo-energy conserving integrator with momentum jumps:
   F. Marazzato, A. Ern, C. Mariotti, L. Monasse, "An explicit
   pseudo-energy conserving time-integration scheme for Hamiltonian
   dynamics", Comput. Methods Appl. Mech. Engrg. 347 (2019) 906-927.
------------------------------------------------------------------------- */

#include "fix_pe_jump.h"

#include "atom.h"
#include "comm.h"
#include "compute.h"
#include "domain.h"
#include "error.h"
#include "force.h"
#include "memory.h"
#include "modify.h"
#include "neigh_list.h"
#include "neighbor.h"
#include "output.h"
#include "pair.h"
#include "pe_jump_force_sampler.h"
#include "pe_jump_quadrature.h"
#include "update.h"

#include <cmath>
#include <cstring>
#include <utility>

using namespace LAMMPS_NS;
using namespace FixConst;
using PEJump::ForceSampler;
using PEJump::Quadrature;

static constexpr double ADAPT_GROWTH = 1.05;         // largest step growth factor per step
static constexpr double ADAPT_SAFETY = 0.5;          // aim at this fraction of the bound
static constexpr double BLOWUP = 1.0e300;            // stands for a non-finite value in reductions
static constexpr double STOP_GROWTH = 1.0e6;         // jump growth that is always instability
static constexpr double HINT_GROWTH = 2.0;           // ... that is instability if atoms move far
static constexpr int ADAPT_SAMPLES = 64;             // trial steps between dtmax and dtmin
static constexpr int ADAPT_BISECT = 40;              // bisections of the largest admissible step
static constexpr double AUTO_DAMP_STEPS = 1000.0;    // damp auto: parasitic damping time in steps

/* ---------------------------------------------------------------------- */

FixPEJump::FixPEJump(LAMMPS *lmp, int narg, char **arg) : FixPEJump(lmp, narg, arg, 3, false) {}

/* ---------------------------------------------------------------------- */

FixPEJump::FixPEJump(LAMMPS *lmp, int narg, char **arg, int first_keyword, bool two_clocks) :
    Fix(lmp, narg, arg), rule(nullptr), sampler(nullptr), fnode(nullptr), node_select(nullptr),
    fhist1(nullptr), fhist2(nullptr), hlast(0.0), hlast2(0.0), vhalf(nullptr), jump(nullptr),
    fstart(nullptr), fsum(nullptr), fsample(nullptr), xsave(nullptr), fsave(nullptr)
{
  if (narg < first_keyword) utils::missing_cmd_args(FLERR, std::string("fix ") + style, error);

  auto family = Quadrature::LEGENDRE;
  int npoints = 1;
  init_style = INIT_KICK;
  sample_mask = ForceSampler::ALL;
  adapt = 0;
  adapt_eps = adapt_dtmin = adapt_dtmax = 0.0;
  compensate = two_clocks ? 0 : 1;
  damp_time = -1.0;
  buffer_layers = 0;
  auto_tol = 0.0;
  auto_steps[0] = auto_steps[1] = auto_steps[2] = 0;
  id_pe = nullptr;
  c_pe = nullptr;
  vprev = 0.0;

  const std::string fix = std::string("fix ") + style;
  int iarg = first_keyword;
  while (iarg < narg) {
    if (strcmp(arg[iarg], "quadrature") == 0) {
      if (iarg + 2 > narg) utils::missing_cmd_args(FLERR, fix + " quadrature", error);
      const std::string which = arg[iarg + 1];
      auto_tol = 0.0;    // the last quadrature keyword wins
      if (which == "midpoint") {
        family = Quadrature::LEGENDRE;
        npoints = 1;
        iarg += 2;
      } else if (which == "auto") {
        if (iarg + 3 > narg) utils::missing_cmd_args(FLERR, fix + " quadrature auto", error);
        auto_tol = utils::numeric(FLERR, arg[iarg + 2], false, lmp);
        if (auto_tol <= 0.0) error->all(FLERR, "Fix {} quadrature auto needs TOL > 0", style);
        family = Quadrature::LOBATTO;
        npoints = 5;
        iarg += 3;
      } else if ((which == "lobatto") || (which == "legendre")) {
        if (iarg + 3 > narg) utils::missing_cmd_args(FLERR, fix + " quadrature " + which, error);
        npoints = utils::inumeric(FLERR, arg[iarg + 2], false, lmp);
        family = (which == "lobatto") ? Quadrature::LOBATTO : Quadrature::LEGENDRE;
        const int nmin = (family == Quadrature::LOBATTO) ? 2 : 1;
        if ((npoints < nmin) || (npoints > Quadrature::MAX_POINTS))
          error->all(FLERR, "Fix {} quadrature {} needs {} to {} points, got {}", style, which,
                     nmin, Quadrature::MAX_POINTS, npoints);
        iarg += 3;
      } else {
        error->all(FLERR, "Unknown fix {} quadrature rule: {}", style, which);
      }
    } else if (strcmp(arg[iarg], "init") == 0) {
      if (iarg + 2 > narg) utils::missing_cmd_args(FLERR, fix + " init", error);
      if (strcmp(arg[iarg + 1], "kick") == 0)
        init_style = INIT_KICK;
      else if (strcmp(arg[iarg + 1], "paper") == 0)
        init_style = INIT_PAPER;
      else
        error->all(FLERR, "Unknown fix {} init style: {}", style, arg[iarg + 1]);
      iarg += 2;
    } else if (strcmp(arg[iarg], "adapt") == 0) {
      if (iarg + 4 > narg) utils::missing_cmd_args(FLERR, fix + " adapt", error);
      adapt = 1;
      adapt_eps = utils::numeric(FLERR, arg[iarg + 1], false, lmp);
      adapt_dtmin = utils::numeric(FLERR, arg[iarg + 2], false, lmp);
      adapt_dtmax = utils::numeric(FLERR, arg[iarg + 3], false, lmp);
      if (adapt_eps <= 0.0) error->all(FLERR, "Fix {} adapt eps must be > 0", style);
      if ((adapt_dtmin <= 0.0) || (adapt_dtmax < adapt_dtmin))
        error->all(FLERR, "Fix {} adapt needs 0 < dtmin <= dtmax", style);
      iarg += 4;
    } else if (strcmp(arg[iarg], "buffer") == 0) {
      if (iarg + 2 > narg) utils::missing_cmd_args(FLERR, fix + " buffer", error);
      if (!two_clocks)
        error->all(FLERR,
                   "Fix {} has a single clock: the buffer keyword belongs to fix pe_jump/async",
                   style);
      buffer_layers = utils::inumeric(FLERR, arg[iarg + 1], false, lmp);
      if (buffer_layers < 0) error->all(FLERR, "Fix {} buffer needs N >= 0", style);
      iarg += 2;
    } else if (strcmp(arg[iarg], "damp") == 0) {
      if (iarg + 2 > narg) utils::missing_cmd_args(FLERR, fix + " damp", error);
      if (strcmp(arg[iarg + 1], "auto") == 0) {
        damp_time = -1.0;
      } else {
        damp_time = utils::numeric(FLERR, arg[iarg + 1], false, lmp);
        if (!(damp_time >= 0.0)) error->all(FLERR, "Fix {} damp needs a time >= 0 or auto", style);
      }
      iarg += 2;
    } else if (strcmp(arg[iarg], "compensate") == 0) {
      if (iarg + 2 > narg) utils::missing_cmd_args(FLERR, fix + " compensate", error);
      compensate = utils::logical(FLERR, arg[iarg + 1], false, lmp);
      iarg += 2;
    } else if (strcmp(arg[iarg], "sample") == 0) {
      sample_mask = 0;
      ++iarg;
      while (iarg < narg) {
        const int bit = ForceSampler::parse(arg[iarg]);
        if (!bit) break;
        sample_mask |= bit;
        ++iarg;
      }
      if (!sample_mask)
        error->all(FLERR,
                   "Fix {} sample needs one or more of pair, bond, angle, dihedral, improper, "
                   "kspace, or all",
                   style);
    } else {
      error->all(FLERR, "Unknown fix {} keyword: {}", style, arg[iarg]);
    }
  }

  rule = new Quadrature(family, npoints);
  sampler = new ForceSampler(lmp);

  if (auto_tol > 0.0) {
    if (sample_mask != ForceSampler::ALL)
      error->all(FLERR, "Fix {} quadrature auto samples all force contributions", style);
    id_pe = utils::strdup(std::string(id) + "_pe");
  }

  time_integrate = 1;
  scalar_flag = 1;
  vector_flag = 1;
  size_vector = 5;
  global_freq = 1;
  extscalar = 1;
  extvector = -1;
  extlist = new int[size_vector]{1, 1, 0, 0, 0};
  restart_global = 1;
  restart_peratom = 1;
  create_attribute = 1;
  comm_reverse = 3;
  force_reneighbor = 1;
  next_reneighbor = -1;

  nstate = (rule->has_end_nodes() ? 9 : 6) + ((adapt || compensate) ? 6 : 0);
  nmax_work = 0;
  started = reinit_pending = 0;
  split_primary = use_copy = 0;
  eflag_step = vflag_step = 0;
  h_step = 0.0;
  stats_valid = 0;
  stats[0] = stats[1] = 0.0;
  jump_ref = 0.0;
  evals_step = evals_total = 0.0;
  energy_scale = 0.0;
  cached_step = -1;

  FixPEJump::grow_arrays(atom->nmax);
  for (int i = 0; i < atom->nlocal; i++) FixPEJump::set_arrays(i);
  fresh_atoms = others_bits = velocity_hooks = damping = impulse_local = 0;
  damp_rate = 0.0;
  advance_pending = 0.0;
  // a derived style registers its callbacks at the end of its own
  // constructor, once all its arguments are accepted
  if (!two_clocks) {
    atom->add_callback(Atom::GROW);
    atom->add_callback(Atom::RESTART);
  }
}

/* ----------------------------------------------------------------------
   what the fix creates besides itself, once it exists: quadrature auto
   needs the potential energy at every step, so a compute pe asks the
   Verlet loop to tally it
------------------------------------------------------------------------- */

void FixPEJump::post_constructor()
{
  if (id_pe) modify->add_compute(fmt::format("{} all pe", id_pe));
}

/* ---------------------------------------------------------------------- */

FixPEJump::~FixPEJump()
{
  if (modify->get_fix_by_id(id)) {
    atom->delete_callback(id, Atom::GROW);
    atom->delete_callback(id, Atom::RESTART);
  }
  memory->destroy(vhalf);
  memory->destroy(jump);
  memory->destroy(fstart);
  memory->destroy(fhist1);
  memory->destroy(fhist2);
  memory->destroy(fsum);
  memory->destroy(fsample);
  memory->destroy(xsave);
  memory->destroy(fsave);
  memory->destroy(fnode);
  if (id_pe && modify->get_compute_by_id(id_pe)) modify->delete_compute(id_pe);
  delete[] id_pe;
  delete[] extlist;
  delete rule;
  delete sampler;
}

/* ---------------------------------------------------------------------- */

int FixPEJump::setmask()
{
  int mask = INITIAL_INTEGRATE | POST_NEIGHBOR | PRE_REVERSE | FINAL_INTEGRATE;
  if (adapt) mask |= END_OF_STEP;
  return mask;
}

/* ---------------------------------------------------------------------- */

void FixPEJump::init()
{
  // how often fixes look at the atoms at the end of a step
  end_of_step_every.clear();
  for (const auto &ifix : modify->get_fix_list())
    if ((ifix != this) && (ifix->setmask() & END_OF_STEP))
      end_of_step_every.push_back(MAX(ifix->nevery, 1));

  inverse_mass.assign(atom->ntypes + 1, 0.0);
  if (atom->mass)
    for (int t = 1; t <= atom->ntypes; t++)
      if (atom->mass[t] > 0.0) inverse_mass[t] = 1.0 / atom->mass[t];

  if (utils::strmatch(update->integrate_style, "^respa"))
    error->all(FLERR, "Fix {} does not support run_style respa: use run_style verlet", style);
  // the jump relation needs a step that goes forward: with h = 0 it flips
  // the jump every step, and a change of sign excites the parasitic mode
  if (!(update->dt > 0.0))
    error->all(FLERR,
               "Fix {} needs a timestep > 0, got {}: to run backwards in time, reverse the "
               "velocities instead (variable rx atom -vx, likewise ry and rz, then velocity all "
               "set v_rx v_ry v_rz), which the fix continues exactly",
               style, update->dt);
  if (adapt)
    for (const auto &ifix : modify->get_fix_list())
      if (utils::strmatch(ifix->style, "^dt/reset"))
        error->all(FLERR, "Fix {} adapt and fix {} ({}) both set the time step: use one of them",
                   style, ifix->id, ifix->style);
  if (atom->torque_flag)
    error->all(FLERR, "Fix {} integrates point particles only; atom style {} has torques", style,
               atom->atom_style);

  sort_other_fixes();

  // forces that the rule does not integrate (other fixes that add forces,
  // contributions left out by sample) act as impulses at the primary node:
  // the force there is split into the sampled part and the rest. The
  // impulse must sit at the centre of the step or at its end, so an even
  // Gauss-Legendre rule then gets the centre as an extra node

  const int present = sampler->present();
  split_primary = !adders.empty() || ((sample_mask & present) != present);
  use_copy = split_primary && ((sample_mask & present) == present);
  const bool centre = split_primary && (rule->family() == Quadrature::LEGENDRE) &&
      (rule->points() % 2 == 0) && (auto_tol == 0.0);
  if (centre != (rule->size() != rule->points())) {
    auto *other = new Quadrature(rule->family(), rule->points(), centre);
    delete rule;
    rule = other;
  }
  // other fixes that add forces or change velocities (thermostats above
  // all) drive the parasitic period-2 mode, which the scheme does not damp:
  // damp it over damp_time (auto: AUTO_DAMP_STEPS steps, from the start if
  // fixes add forces, else from the first step where a velocity changed)
  damp_rate = 0.0;
  if (damp_time > 0.0)
    damp_rate = 1.0 / damp_time;
  else if (damp_time < 0.0)
    damp_rate = 1.0 / (AUTO_DAMP_STEPS * update->dt);
  damping = (damp_time > 0.0) || ((damp_time < 0.0) && !adders.empty());
  impulse_local = 0;
  if (id_pe) {
    c_pe = modify->get_compute_by_id(id_pe);
    if (!c_pe) error->all(FLERR, "Fix {}: compute {} was deleted", style, id_pe);
  }
  if (present && !(sample_mask & present) && (comm->me == 0))
    error->warning(FLERR, "Fix {} samples none of the force contributions present", style);
}

/* ----------------------------------------------------------------------
   other fixes that act on the forces: those that replace or project them
   act at every quadrature node (projections), those that add forces act
   once per step as impulses (adders). Constraints are refused, other time
   integrators are remembered for the interaction check
------------------------------------------------------------------------- */

void FixPEJump::sort_other_fixes()
{
  std::vector<Fix *> preparations, projections;
  adders.clear();
  others_bits = 0;
  velocity_hooks = 0;
  for (auto *ifix : modify->get_fix_list()) {
    if (ifix == this) continue;
    velocity_hooks |= ifix->setmask() & (BETWEEN_STEPS | INSIDE_STEP);
    if (ifix->setmask() & PRE_FORCE) preparations.push_back(ifix);
    if (ifix->time_integrate) {
      others_bits |= ifix->groupbit;
      continue;
    }
    if (ifix->dof_flag)
      error->all(FLERR,
                 "Fix {} cannot be combined with the constraints of fix {} ({}): they assume the "
                 "velocity Verlet update of fix nve. Use fix nve, or remove the constraints",
                 style, ifix->id, ifix->style);
    if (!(ifix->setmask() & POST_FORCE)) continue;
    if (utils::strmatch(ifix->style, "^setforce") || utils::strmatch(ifix->style, "^aveforce") ||
        utils::strmatch(ifix->style, "^freeze") || utils::strmatch(ifix->style, "^lineforce") ||
        utils::strmatch(ifix->style, "^planeforce") || utils::strmatch(ifix->style, "^enforce2d"))
      projections.push_back(ifix);
    else
      adders.push_back(ifix);
  }
  sampler->set_hooks(preparations, projections);
}

/* ----------------------------------------------------------------------
   atoms of another time integrator (fix nve, fix rigid, a second fix
   pe_jump) sit at the end of the step when forces are computed. Forces
   between them and this fix's atoms are consistent only if every node of
   the rule is a step end (lobatto 2); otherwise refuse interactions
   between the two sets. Checked at setup and after each list build.
------------------------------------------------------------------------- */

void FixPEJump::check_other_integrators()
{
  if (!others_bits || ((rule->family() == Quadrature::LOBATTO) && (rule->size() == 2))) return;

  const int *mask = atom->mask;
  const auto cross = [&](int i, int j) {
    return ((mask[i] & groupbit) && (mask[j] & others_bits)) ||
        ((mask[i] & others_bits) && (mask[j] & groupbit));
  };
  int local = 0;
  for (int n = 0; (n < neighbor->nlist) && !local; n++) {
    const NeighList *list = neighbor->lists[n];
    // lists of pair styles, built at every reneighboring (others may be stale)
    if (!list || !list->numneigh || list->kokkos || list->occasional ||
        (list->requestor_type != NeighList::PAIR))
      continue;
    for (int ii = 0; (ii < list->inum) && !local; ii++) {
      const int i = list->ilist[ii];
      for (int jj = 0; jj < list->numneigh[i]; jj++)
        if (cross(i, list->firstneigh[i][jj] & NEIGHMASK)) local = 1;
    }
  }
  if (atom->molecular != Atom::ATOMIC)
    for (int n = 0; (n < neighbor->nbondlist) && !local; n++)
      if (cross(neighbor->bondlist[n][0], neighbor->bondlist[n][1])) local = 1;
  int global = 0;
  MPI_Allreduce(&local, &global, 1, MPI_INT, MPI_MAX, world);
  if (global)
    error->all(FLERR,
               "Fix {} with quadrature {} evaluates forces inside the step, but atoms of another "
               "time integrator interact with its atoms at step {}: their positions are those "
               "of the step end, so the forces between the two sets would mix times. Use "
               "quadrature lobatto 2 (forces at the step ends only), or integrate all "
               "interacting atoms with one fix {}",
               style, rule->name(), update->ntimestep, style);
}

/* ----------------------------------------------------------------------
   forces at the current positions q^n are known here. Start the two-step
   scheme, or continue it if the state carried over (earlier run, restart)
------------------------------------------------------------------------- */

void FixPEJump::setup(int /*vflag*/)
{
  grow_work();
  stats_valid = 0;
  jump_ref = 0.0;
  evals_step = 0.0;
  agree_on_started();
  if (!started) {
    start_scheme(nullptr, true);
  } else {
    const int change = detect_velocity_change();
    if (change == 2)
      start_scheme("velocities were changed since the last run: restarting the two-step scheme "
                   "from the current positions and velocities",
                   true);
    else
      refresh_start_nodes();
    if ((change == 1) && (comm->me == 0))
      utils::logmesg(lmp, "Fix {}: all velocities were reversed: continuing backwards in time\n",
                     style);
  }
  fresh_atoms = 0;
  check_other_integrators();
  if (adapt) {
    // the first step is taken with the timestep as given: keep it in range
    const double dt = MIN(MAX(update->dt, adapt_dtmin), adapt_dtmax);
    if (dt != update->dt) {
      if (comm->me == 0)
        utils::logmesg(lmp, "Fix {}: timestep {} is outside the adapt range [{}, {}]: using {}\n",
                       style, update->dt, adapt_dtmin, adapt_dtmax, dt);
      set_timestep(dt);
    }
    energy_scale = fabs(pseudo_energy_now());
  }
  if (auto_tol > 0.0) {
    vprev = potential_now(sample_mask);
    c_pe->addstep(update->ntimestep + 1);
  }
}

/* ---------------------------------------------------------------------- */

void FixPEJump::setup_pre_reverse(int eflag, int vflag)
{
  pre_reverse(eflag, vflag);
}

/* ----------------------------------------------------------------------
   move from q^n to the primary quadrature node, where the Verlet loop will
   evaluate the forces
------------------------------------------------------------------------- */

void FixPEJump::initial_integrate(int /*vflag*/)
{
  if (reinit_pending) start_scheme(nullptr, false);
  reinit_pending = 0;

  h_step = update->dt;
  node_impulses();
  if (compensate && (hlast2 > 0.0)) compensate_step_change();
  check_lists();
  advance(rule->node[rule->primary()] * h_step);
}

/* ----------------------------------------------------------------------
   restart data that does not fit the fix clears started only on the ranks
   that own atoms: every rank must take the same decision
------------------------------------------------------------------------- */

void FixPEJump::agree_on_started()
{
  int all_started = 0;
  MPI_Allreduce(&started, &all_started, 1, MPI_INT, MPI_MIN, world);
  started = all_started;

  // velocities that are not finite (a velocity command gone wrong, e.g.
  // velocity scale to a negative temperature) would only show up later
  double **v = atom->v;
  const int *mask = atom->mask;
  bigint bad = 0, all_bad = 0;
  for (int i = 0; i < atom->nlocal; i++)
    if ((mask[i] & groupbit) &&
        !(std::isfinite(v[i][0]) && std::isfinite(v[i][1]) && std::isfinite(v[i][2])))
      ++bad;
  MPI_Allreduce(&bad, &all_bad, 1, MPI_LMP_BIGINT, MPI_SUM, world);
  if (all_bad)
    error->all(FLERR,
               "Fix {}: {} atoms have velocities that are not finite at the start of the run",
               style, all_bad);
}

/* ----------------------------------------------------------------------
   impulses at the node q^n: a velocity that another fix (or a command
   between runs that did not restart the scheme) changed since the last
   step changes the free-flight velocity by the same amount and leaves the
   jump alone; with a Lobatto rule, forces that the rule does not integrate
   give the second half of their kick (the first half went into the node
   velocity at the end of the last step, as in velocity Verlet)
------------------------------------------------------------------------- */

void FixPEJump::node_impulses()
{
  double **v = atom->v;
  double **f = atom->f;
  const int *mask = atom->mask;
  const int nlocal = atom->nlocal;
  const bool half_kick = split_primary && rule->has_end_nodes();
  const double dth = 0.5 * h_step * force->ftm2v;
  const bool compare = velocity_hooks & BETWEEN_STEPS;
  if (!compare && !half_kick) return;
  bool changed = half_kick;
  for (int i = 0; i < nlocal; i++) {
    if (!(mask[i] & groupbit)) continue;
    for (int k = 0; k < 3; k++)
      if (compare && (v[i][k] != vhalf[i][k] - 0.5 * jump[i][k])) {
        vhalf[i][k] = v[i][k] + 0.5 * jump[i][k];
        changed = true;
        impulse_local = 1;
      }
    if (half_kick && !std::isnan(fstart[i][0])) {
      const double dtfm = dth * inverse_mass_of(i);
      for (int k = 0; k < 3; k++) vhalf[i][k] += dtfm * (f[i][k] - fstart[i][k]);
    }
  }
  // the speeds taken at the end of the last step no longer bound the
  // excursion of this step's nodes
  if (changed) stats_valid = 0;
}

/* ----------------------------------------------------------------------
   free flight of the atoms of the group over time t; during the step the
   velocity seen by other fixes is the free-flight velocity (as with fix
   nve, whose forces see v^{n+1/2}), and a change they make to it is an
   impulse there
------------------------------------------------------------------------- */

void FixPEJump::advance(double t)
{
  double **x = atom->x;
  double **v = atom->v;
  const int *mask = atom->mask;
  const int nlocal = atom->nlocal;
  // on a step that rebuilds the lists, they are built (and atoms exchanged
  // and sorted) at the end node q^{n+1}, as with fix nve, so that a run
  // continued from a restart, which builds them there, reproduces the
  // unbroken run; the atoms go back to the primary node after the build
  const bool later = (t != h_step) && rebuild_due();
  const double now = later ? h_step : t;
  advance_pending = later ? t - h_step : 0.0;
  for (int i = 0; i < nlocal; i++)
    if (mask[i] & groupbit)
      for (int k = 0; k < 3; k++) {
        v[i][k] = vhalf[i][k];
        x[i][k] += now * vhalf[i][k];
      }
}

/* ----------------------------------------------------------------------
   the lists were built at the end node: back to the primary node
------------------------------------------------------------------------- */

void FixPEJump::post_neighbor()
{
  if (advance_pending == 0.0) return;
  double **x = atom->x;
  const int *mask = atom->mask;
  for (int i = 0; i < atom->nlocal; i++)
    if (mask[i] & groupbit)
      for (int k = 0; k < 3; k++) x[i][k] += advance_pending * vhalf[i][k];
  advance_pending = 0.0;
  comm->forward_comm();
}

/* ----------------------------------------------------------------------
   true if the Verlet loop will rebuild the neighbor lists in this step
   whatever the atoms' positions: the decision of Neighbor::decide() for
   lists without a distance check (neigh_modify check no). With a distance
   check the decision depends on the positions and is left to LAMMPS.
------------------------------------------------------------------------- */

bool FixPEJump::rebuild_due() const
{
  if (neighbor->dist_check || neighbor->build_once) return false;
  const bigint now = update->ntimestep;
  if (output->restart_flag && (now == output->next_restart)) return true;
  for (const auto *ifix : modify->get_fix_list())
    if (ifix->force_reneighbor && (now == ifix->next_reneighbor)) return true;
  const int ago = neighbor->ago + 1;
  return (ago >= neighbor->delay) && (ago % neighbor->every == 0);
}

/* ---------------------------------------------------------------------- */

const int *FixPEJump::atom_mask() const
{
  return atom->mask;
}

/* ---------------------------------------------------------------------- */

int FixPEJump::owned_atoms() const
{
  return atom->nlocal;
}

/* ---------------------------------------------------------------------- */

double FixPEJump::inverse_mass_of(int i) const
{
  return atom->rmass ? 1.0 / atom->rmass[i] : inverse_mass[atom->type[i]];
}

/* ----------------------------------------------------------------------
   compensate keyword: with steps h_{n-1}, h_n, h_{n+1} the smooth solution
   of the jump relation is [v]^n = (h_{n-1} + h_n)/2 a(t_n); the jump
   [v]^{n+1} = 2 h_n A_n - [v]^n of the last step (A_n its averaged
   acceleration) falls short of it by
     d = (h_{n+1} - h_n)/2 a(t_{n+1}) - (h_n - h_{n-1})/2 a(t_n),
   which feeds the parasitic period-2 mode whenever the step size changes.
   Add d, with a(t_n), a(t_{n+1}) interpolated linearly from the averages
   A_{n-1}, A_n of the last two steps (at their mid-step times), less the
   part along the peculiar velocities w = v^{n+1/2} - V_cm that would
   change the pseudo-energy (1/2) sum m v^{n+1/2}.v^{n+3/2}; the total
   momentum is kept too, since sum m a = 0 and sum m w = 0.
------------------------------------------------------------------------- */

void FixPEJump::compensate_step_change()
{
  const double h0 = hlast2, h1 = hlast, h2 = h_step;    // h_{n-1}, h_n, h_{n+1}
  if ((h2 - h1 == 0.0) && (h1 - h0 == 0.0)) return;
  const double slope = 1.0 / (0.5 * (h0 + h1));    // per (A_n - A_{n-1})
  const double c_end = 0.5 * (h2 - h1), c_start = 0.5 * (h1 - h0);

  double **v = atom->v;
  const double *rmass = atom->rmass;
  const int *type = atom->type;
  const int *mask = atom->mask;
  const int nlocal = atom->nlocal;
  const double ftm2v = force->ftm2v;

  // d (velocity units) into fsum, which is free until the quadrature of this step
  // sums m of: v.d, v.v, and sum m v, sum m (v = v^{n+1/2})
  double local[6] = {0.0, 0.0, 0.0, 0.0, 0.0, 0.0};
  for (int i = 0; i < nlocal; i++) {
    if (!(mask[i] & groupbit)) continue;
    const double m = rmass ? rmass[i] : atom->mass[type[i]];
    const double minv = rmass ? 1.0 / rmass[i] : inverse_mass[type[i]];
    for (int k = 0; k < 3; k++) {
      const double an = ftm2v * minv * fhist1[i][k];
      const double ds = 0.5 * h1 * slope * (an - ftm2v * minv * fhist2[i][k]);
      fsum[i][k] = c_end * (an + ds) - c_start * (an - ds);
      const double vk = vhalf[i][k] - jump[i][k];
      local[0] += m * vk * fsum[i][k];
      local[1] += m * vk * vk;
      local[2 + k] += m * vk;
    }
    local[5] += m;
  }
  double sum[6];
  MPI_Allreduce(local, sum, 6, MPI_DOUBLE, MPI_SUM, world);
  const double vcm[3] = {sum[2] / sum[5], sum[3] / sum[5], sum[4] / sum[5]};
  const double ww = sum[1] - (sum[2] * sum[2] + sum[3] * sum[3] + sum[4] * sum[4]) / sum[5];
  const double alpha = (ww > 0.0) ? sum[0] / ww : 0.0;

  for (int i = 0; i < nlocal; i++) {
    if (!(mask[i] & groupbit)) continue;
    for (int k = 0; k < 3; k++) {
      const double delta = fsum[i][k] - alpha * (vhalf[i][k] - jump[i][k] - vcm[k]);
      jump[i][k] += delta;
      vhalf[i][k] += delta;
      v[i][k] = vhalf[i][k] - 0.5 * jump[i][k];
    }
  }
  cached_step = -1;
  stats_valid = 0;
}

/* ----------------------------------------------------------------------
   forces of this step are evaluated at q^n + c h v^{n+1/2} for c from the
   first node sampled (the start node of a Lobatto rule is reused) to the
   last one, or to the end node q^{n+1} if the step tallies energy or virial
------------------------------------------------------------------------- */

void FixPEJump::check_lists()
{
  const int first = rule->has_end_nodes() ? 1 : 0;
  const double c_hi = tally_step() ? 1.0 : rule->node.back();
  check_excursion(rule->node[first] * h_step, c_hi * h_step);
}

/* ---------------------------------------------------------------------- */

bool FixPEJump::tally_step() const
{
  const bigint now = update->ntimestep;
  return (update->eflag_global == now) || (update->eflag_atom == now) ||
      (update->vflag_global == now) || (update->vflag_atom == now);
}

/* ----------------------------------------------------------------------
   remember which energy/virial tallies this step needs and, if the primary
   force must be split, copy the force field part before other fixes add to it
------------------------------------------------------------------------- */

void FixPEJump::pre_reverse(int eflag, int vflag)
{
  eflag_step = eflag;
  vflag_step = vflag;
  if (!use_copy) return;
  grow_work();
  const int nall = atom->nlocal + atom->nghost;
  if (nall) memcpy(&fsample[0][0], &atom->f[0][0], 3 * sizeof(double) * nall);
}

/* ----------------------------------------------------------------------
   forces at the primary node are known: sample the other nodes, jump the
   momenta, and move on to the end node q^{n+1}
------------------------------------------------------------------------- */

void FixPEJump::final_integrate()
{
  grow_work();
  evals_step = 1.0;

  // velocities changed by other fixes during the step (wall/reflect, ...)
  if (velocity_hooks & INSIDE_STEP) {
    double **v = atom->v;
    const int *mask = atom->mask;
    for (int i = 0; i < atom->nlocal; i++)
      if (mask[i] & groupbit)
        for (int k = 0; k < 3; k++)
          if (v[i][k] != vhalf[i][k]) vhalf[i][k] = v[i][k];
  }

  // with a single node, evaluated by the Verlet loop with nothing else to
  // separate, the forces there are the quadrature average itself
  const bool direct = (rule->size() == 1) && !split_primary && !adapt;
  if (!direct) quadrature_sum();
  double **favg = direct ? atom->f : fsum;

  const double rest = (1.0 - rule->node[rule->primary()]) * h_step;
  if (fhist1) std::swap(fhist1, fhist2);
  double mag[2] = {0.0, 0.0};
  finish_step(nullptr, favg, rest, mag);
  stats[0] = std::isfinite(mag[0]) ? mag[0] : BLOWUP;
  stats[1] = std::isfinite(mag[1]) ? mag[1] : BLOWUP;
  stats_valid = 1;

  if (rest != 0.0) tally_at_node();
  if (others_bits && (neighbor->ago == 0)) check_other_integrators();
  evals_total += evals_step;
  cached_step = -1;
  hlast2 = hlast;
  hlast = h_step;
}

/* ----------------------------------------------------------------------
   the owned atoms of the group (those listed in only, if given) jump with
   the quadrature sums favg of their forces over the step h_step and move on
   by rest from the primary node to q^{n+1}; the start-node forces of the
   next step and the force history are kept. mag[0], mag[1]: the largest
   |v^{n+3/2}|^2 and |[v]^{n+1}|^2 so far, for check_excursion()
------------------------------------------------------------------------- */

void FixPEJump::finish_step(const AtomList *only, double **favg, double rest, double *mag)
{
  double **x = atom->x;
  double **v = atom->v;
  double **f = atom->f;
  const double kick = 2.0 * h_step * force->ftm2v;
  const int keep_start = rule->has_end_nodes();
  // forces not integrated by the rule: an impulse at the centre of the step
  // (position Verlet), or at its end node half now and half at the start of
  // the next step (velocity Verlet)
  const bool centre_kick = split_primary && !keep_start;
  const bool end_kick = split_primary && keep_start;
  // parasitic damping: [v]^{n+1} = (2 - beta) h a - (1 - beta) [v]^n keeps
  // the smooth jump h a and multiplies the alternating one by -(1 - beta)
  const double beta = damping ? MIN(1.0, damp_rate * fabs(h_step)) : 0.0;
  double vv = mag[0], jj = mag[1];
  const auto one = [&](int i) {
    const double dtfm = kick * inverse_mass_of(i);
    if (centre_kick)
      for (int k = 0; k < 3; k++) vhalf[i][k] += 0.5 * dtfm * (f[i][k] - fsample[i][k]);
    for (int k = 0; k < 3; k++) x[i][k] += rest * vhalf[i][k];
    if (beta > 0.0)
      for (int k = 0; k < 3; k++) jump[i][k] *= 1.0 - beta;
    two_step_jump((1.0 - 0.5 * beta) * dtfm, favg[i], jump[i], vhalf[i], v[i]);
    if (end_kick)
      for (int k = 0; k < 3; k++) {
        vhalf[i][k] += 0.25 * dtfm * (f[i][k] - fsample[i][k]);
        v[i][k] = vhalf[i][k] - 0.5 * jump[i][k];
      }
    for (int k = 0; k < 3; k++) {
      if (keep_start) fstart[i][k] = fsample[i][k];
      if (fhist1) fhist1[i][k] = favg[i][k];
    }
    vv = MAX(vv, vhalf[i][0] * vhalf[i][0] + vhalf[i][1] * vhalf[i][1] + vhalf[i][2] * vhalf[i][2]);
    jj = MAX(jj, jump[i][0] * jump[i][0] + jump[i][1] * jump[i][1] + jump[i][2] * jump[i][2]);
  };
  for_atoms(only, one);
  mag[0] = vv;
  mag[1] = jj;
}

/* ---------------------------------------------------------------------- */

void FixPEJump::jump_atom(int i, double h, const double *favg)
{
  const double dtfm = 2.0 * h * force->ftm2v * inverse_mass_of(i);
  two_step_jump(dtfm, favg, jump[i], vhalf[i], atom->v[i]);
}

/* ----------------------------------------------------------------------
   true if anything looks at the atoms after this step: output, the end of
   the run, or a fix acting at the end of this step
------------------------------------------------------------------------- */

bool FixPEJump::step_observed() const
{
  const bigint now = update->ntimestep;
  if ((now == output->next) || (now == update->laststep)) return true;
  for (const int every : end_of_step_every)
    if (now % every == 0) return true;
  return false;
}

/* ----------------------------------------------------------------------
   the atoms are at the node q^{n+1} but the last force evaluation was
   elsewhere: on steps that tally energy or virial evaluate everything
   once more at the node; on output steps bring the ghosts to the node
------------------------------------------------------------------------- */

void FixPEJump::tally_at_node()
{
  const int nlocal = atom->nlocal;
  if (eflag_step || vflag_step) {
    if (nlocal) memcpy(&fsave[0][0], &atom->f[0][0], 3 * sizeof(double) * nlocal);
    sampler->compute(ForceSampler::ALL, eflag_step, vflag_step);
    if (nlocal) memcpy(&atom->f[0][0], &fsave[0][0], 3 * sizeof(double) * nlocal);
    evals_step += 1.0;
  } else if (step_observed()) {
    comm->forward_comm();
  }
}

/* ----------------------------------------------------------------------
   quadrature auto: say how often each rule was taken in this run
------------------------------------------------------------------------- */

void FixPEJump::post_run()
{
  if ((auto_tol > 0.0) && (comm->me == 0))
    utils::logmesg(lmp,
                   "Fix {} quadrature auto {}: steps with lobatto 2: {}, lobatto 3: {}, "
                   "lobatto 5: {}\n",
                   style, auto_tol, auto_steps[0], auto_steps[1], auto_steps[2]);
  auto_steps[0] = auto_steps[1] = auto_steps[2] = 0;
}

/* ---------------------------------------------------------------------- */

void FixPEJump::end_of_step()
{
  if (adapt) choose_next_dt();
}

/* ----------------------------------------------------------------------
   (re)start the two-step scheme from the current positions q^0, velocities
   v^0 and forces F(q^0):
     kick:  v^{1/2} = v^0 + (h/2) F/m, [v]^0 = h F/m
     paper: v^{1/2} = v^0,            [v]^0 = 0
   the node velocity v^0 = v^{1/2} - [v]^0/2 is stored back so that a later
   run can tell whether velocities were changed in between.
   with_start: also store the sampled force at q^0 as the Lobatto start node
   (not when only the kick is redone with the complete forces)
------------------------------------------------------------------------- */

void FixPEJump::start_scheme(const char *why, bool with_start)
{
  if (why && (comm->me == 0)) utils::logmesg(lmp, "Fix {}: {}\n", style, why);

  grow_work();
  if (with_start && rule->has_end_nodes())
    store_start_node();
  else if (with_start && split_primary)
    primary_sampled_force();

  // the jump takes the forces that the rule integrates
  double **v = atom->v;
  double **f = split_primary ? fsample : atom->f;
  const double *rmass = atom->rmass;
  const double *mass = atom->mass;
  const int *type = atom->type;
  const int *mask = atom->mask;
  const int nlocal = atom->nlocal;
  const double kick = (init_style == INIT_KICK) ? force->ftm2v : 0.0;

  for (int i = 0; i < nlocal; i++) {
    if (!(mask[i] & groupbit)) continue;
    const double dtfm = kick * kick_step(i) / (rmass ? rmass[i] : mass[type[i]]);
    for (int k = 0; k < 3; k++) {
      jump[i][k] = dtfm * f[i][k];
      vhalf[i][k] = v[i][k] + 0.5 * jump[i][k];
      v[i][k] = vhalf[i][k] - 0.5 * jump[i][k];
    }
  }

  // fixes defined after this one act on the forces after its setup(): redo
  // the initial kick with the complete forces at the first step

  reinit_pending =
      with_start && (init_style == INIT_KICK) && !split_primary && sampler->has_projections();
  started = 1;
  hlast = hlast2 = 0.0;
  stats_valid = 0;
  cached_step = -1;
}

/* ---------------------------------------------------------------------- */

double FixPEJump::kick_step(int /*i*/) const
{
  return update->dt;
}

/* ----------------------------------------------------------------------
   Lobatto rules: the sampled force at q^0 is the start node of the first step
------------------------------------------------------------------------- */

void FixPEJump::store_start_node()
{
  primary_sampled_force();
  const int *mask = atom->mask;
  const int nlocal = atom->nlocal;
  for (int i = 0; i < nlocal; i++)
    if (mask[i] & groupbit)
      for (int k = 0; k < 3; k++) fstart[i][k] = fsample[i][k];
}

/* ----------------------------------------------------------------------
   sampled force-field force at the primary node into fsample (owned atoms)
------------------------------------------------------------------------- */

void FixPEJump::primary_sampled_force()
{
  const int nlocal = atom->nlocal;
  const size_t nbytes = 3 * sizeof(double) * nlocal;
  if (!nlocal && !split_primary) return;

  if (!split_primary) {
    memcpy(&fsample[0][0], &atom->f[0][0], nbytes);
  } else if (use_copy) {
    if (force->newton) comm->reverse_comm(this);
  } else {
    if (nlocal) memcpy(&fsave[0][0], &atom->f[0][0], nbytes);
    sampler->compute(sample_mask, 0, 0);
    if (nlocal) {
      memcpy(&fsample[0][0], &atom->f[0][0], nbytes);
      memcpy(&atom->f[0][0], &fsave[0][0], nbytes);
    }
    evals_step += sampler->fraction(sample_mask);
  }
  // at setup, fixes after this one have not yet acted on the forces
  if (sampler->has_projections() && (split_primary || update->setupflag)) project_sampled();
}

/* ----------------------------------------------------------------------
   the force-replacing fixes act on the sampled force at the primary node
   as they did on the total force there
------------------------------------------------------------------------- */

void FixPEJump::project_sampled()
{
  double **f = atom->f;
  const size_t nbytes = 3 * sizeof(double) * atom->nlocal;
  if (!nbytes) {
    sampler->project();
    return;
  }
  memcpy(&fsave[0][0], &f[0][0], nbytes);
  memcpy(&f[0][0], &fsample[0][0], nbytes);
  sampler->project();
  memcpy(&fsample[0][0], &f[0][0], nbytes);
  memcpy(&f[0][0], &fsave[0][0], nbytes);
}

/* ----------------------------------------------------------------------
   atoms created since the last step (fix deposit, create_atoms) have no
   start-node force: at setup all start nodes are taken again at q^n, and
   during a run a new atom's start node is its first primary node
------------------------------------------------------------------------- */

void FixPEJump::refresh_start_nodes()
{
  int any = 0;
  MPI_Allreduce(&fresh_atoms, &any, 1, MPI_INT, MPI_MAX, world);
  if (!any || !rule->has_end_nodes()) return;

  // the new atoms (start node still unknown) also get the initial kick
  AtomList fresh;
  const int *mask = atom->mask;
  for (int i = 0; i < atom->nlocal; i++)
    if ((mask[i] & groupbit) && std::isnan(fstart[i][0])) fresh.push_back(i);
  store_start_node();
  if (init_style != INIT_KICK) return;
  double **v = atom->v;
  for (const int i : fresh) {
    const double dtfm = force->ftm2v * update->dt * inverse_mass_of(i);
    for (int k = 0; k < 3; k++) {
      jump[i][k] = dtfm * fstart[i][k];
      vhalf[i][k] = v[i][k] + 0.5 * jump[i][k];
      v[i][k] = vhalf[i][k] - 0.5 * jump[i][k];
    }
  }
}

/* ----------------------------------------------------------------------
   fsum = sum_k w_k F_sampled(q_k) + (F(q_p) - F_sampled(q_p)) over the nodes
   q_k = q^n + c_k h v^{n+1/2}; the primary node p was evaluated by the Verlet
   loop, a Lobatto start node is the previous step's end node
------------------------------------------------------------------------- */

void FixPEJump::quadrature_sum()
{
  if (auto_tol > 0.0) {
    auto_quadrature_sum();
    return;
  }

  double **f = atom->f;
  const int *mask = atom->mask;
  const int nlocal = atom->nlocal;
  const int p = rule->primary();
  const double wp = rule->weight[p];
  const int reuse_start = rule->has_end_nodes();

  if (split_primary || reuse_start) primary_sampled_force();

  double **fp = split_primary ? fsample : f;
  const auto start_sum = [&](int i) {
    if (reuse_start && std::isnan(fstart[i][0]))
      for (int k = 0; k < 3; k++) fstart[i][k] = fp[i][k];
    for (int k = 0; k < 3; k++) {
      fsum[i][k] = wp * fp[i][k];
      if (reuse_start) fsum[i][k] += rule->weight[0] * fstart[i][k];
    }
  };
  for_atoms(node_select, start_sum);

  const int first = reuse_start ? 1 : 0;
  if (rule->size() - first <= 1) return;
  sample_nodes(first, p, h_step, -rule->node[p] * h_step, node_select, fsum, nullptr);
}

/* ----------------------------------------------------------------------
   quadrature auto: the nested Gauss-Lobatto rules with 2 (nodes 0, 1),
   3 (also 1/2) and 5 points (also (1 -+ sqrt(3/7))/2). The start node is
   the previous end node, the end node the Verlet evaluation, which also
   tallies the potential energy V(q^{n+1}) (the fix requests it every step).
   The pseudo-energy defect of this step with rule r is then known before
   the jump: D_r = V(q^{n+1}) - V(q^n) + h sum_i v_i^{n+1/2} . I_r,i with
   I_r the quadrature average of the forces. The step takes the first rule
   of 2, 3, 5 points with |D_r| <= TOL (1, 2 or 4 evaluations), else the
   5-point rule.
------------------------------------------------------------------------- */

void FixPEJump::auto_quadrature_sum()
{
  double **f = atom->f;
  const int *mask = atom->mask;
  const int nlocal = atom->nlocal;
  const double h = h_step;
  const std::vector<double> &c = rule->node;    // lobatto 5: 0, c1, 1/2, c3, 1
  const std::vector<double> &w = rule->weight;

  primary_sampled_force();    // F(1) into fsample
  for (int i = 0; i < nlocal; i++)
    if ((mask[i] & groupbit) && std::isnan(fstart[i][0]))
      for (int k = 0; k < 3; k++) fstart[i][k] = fsample[i][k];
  const double vnew = (update->eflag_global == update->ntimestep) ? sampler->energy(sample_mask)
                                                                  : potential_now(sample_mask);
  const double dv = vnew - vprev;
  vprev = vnew;
  c_pe->addstep(update->ntimestep + 1);

  // defect of the rule whose quadrature average is in fsum
  const auto defect = [&]() {
    double local = 0.0, global = 0.0;
    for (int i = 0; i < nlocal; i++)
      if (mask[i] & groupbit)
        local += vhalf[i][0] * fsum[i][0] + vhalf[i][1] * fsum[i][1] + vhalf[i][2] * fsum[i][2];
    MPI_Allreduce(&local, &global, 1, MPI_DOUBLE, MPI_SUM, world);
    return fabs(dv + h * global);
  };

  for (int i = 0; i < nlocal; i++)
    if (mask[i] & groupbit)
      for (int k = 0; k < 3; k++) fsum[i][k] = 0.5 * (fstart[i][k] + fsample[i][k]);
  int used = 0;
  if (defect() > auto_tol) {
    save_positions(nullptr);
    if (nlocal) memcpy(&fsave[0][0], &f[0][0], 3 * sizeof(double) * nlocal);

    evaluate_at((c[2] - 1.0) * h, nullptr);
    for (int i = 0; i < nlocal; i++)
      if (mask[i] & groupbit)
        for (int k = 0; k < 3; k++) {
          fnode[i][k] = f[i][k];
          fsum[i][k] = (fstart[i][k] + 4.0 * f[i][k] + fsample[i][k]) / 6.0;
        }
    used = 1;
    if (defect() > auto_tol) {
      for (int i = 0; i < nlocal; i++)
        if (mask[i] & groupbit)
          for (int k = 0; k < 3; k++)
            fsum[i][k] = w[0] * fstart[i][k] + w[2] * fnode[i][k] + w[4] * fsample[i][k];
      for (int node : {1, 3}) {
        evaluate_at((c[node] - 1.0) * h, nullptr);
        for (int i = 0; i < nlocal; i++)
          if (mask[i] & groupbit)
            for (int k = 0; k < 3; k++) fsum[i][k] += w[node] * f[i][k];
      }
      used = 2;
    }
    restore_positions(nullptr);
    if (nlocal) memcpy(&f[0][0], &fsave[0][0], 3 * sizeof(double) * nlocal);
  }
  ++auto_steps[used];
}

/* ----------------------------------------------------------------------
   move the owned atoms of the group (those listed in only, if given) to
   xsave + shift v^{n+1/2} and evaluate the sampled forces there
------------------------------------------------------------------------- */

void FixPEJump::evaluate_at(double shift, const AtomList *only)
{
  double **x = atom->x;
  const auto move = [&](int i) {
    x[i][0] = xsave[i][0] + shift * vhalf[i][0];
    x[i][1] = xsave[i][1] + shift * vhalf[i][1];
    x[i][2] = xsave[i][2] + shift * vhalf[i][2];
  };
  for_atoms(only, move);
  sampler->compute(sample_mask, 0, 0);
  evals_step += node_cost();
}

/* ----------------------------------------------------------------------
   acc += sum_k w_k F(q_k) over the nodes k = first .. N-1 except skip, with
   q_k = x + (scale c_k + offset) v^{n+1/2} for the owned atoms of the group
   (those listed in only, if given); all other atoms stay where they are.
   fend (if given) receives the forces at the last node. Positions and
   forces are restored afterwards
------------------------------------------------------------------------- */

void FixPEJump::sample_nodes(int first, int skip, double scale, double offset, const AtomList *only,
                             double **acc, double **fend)
{
  double **f = atom->f;
  const int *mask = atom->mask;
  const int nlocal = atom->nlocal;
  const int last = rule->size() - 1;

  save_positions(only);
  if (nlocal) memcpy(&fsave[0][0], &f[0][0], 3 * sizeof(double) * nlocal);

  for (int node = first; node <= last; node++) {
    if (node == skip) continue;
    evaluate_at(scale * rule->node[node] + offset, only);
    const double w = rule->weight[node];
    const bool at_end = fend && (node == last);
    const auto add = [&](int i) {
      acc[i][0] += w * f[i][0];
      acc[i][1] += w * f[i][1];
      acc[i][2] += w * f[i][2];
      if (at_end)
        for (int k = 0; k < 3; k++) fend[i][k] = f[i][k];
    };
    for_atoms(only, add);
  }

  restore_positions(only);
  if (nlocal) memcpy(&f[0][0], &fsave[0][0], 3 * sizeof(double) * nlocal);
}

/* ----------------------------------------------------------------------
   positions of the owned atoms that evaluate_at() moves, kept in xsave.
   The ghosts are not restored: they are brought up to date by the forward
   communication before their next use (the next force evaluation, and on
   steps with output or end-of-step fixes, tally_at_node())
------------------------------------------------------------------------- */

void FixPEJump::save_positions(const AtomList *only)
{
  double **x = atom->x;
  const int nlocal = atom->nlocal;
  if (!only) {
    if (nlocal) memcpy(&xsave[0][0], &x[0][0], 3 * sizeof(double) * nlocal);
    return;
  }
  for (const int i : *only)
    for (int k = 0; k < 3; k++) xsave[i][k] = x[i][k];
}

/* ---------------------------------------------------------------------- */

void FixPEJump::restore_positions(const AtomList *only)
{
  double **x = atom->x;
  const int nlocal = atom->nlocal;
  if (!only) {
    if (nlocal) memcpy(&x[0][0], &xsave[0][0], 3 * sizeof(double) * nlocal);
    return;
  }
  for (const int i : *only)
    for (int k = 0; k < 3; k++) x[i][k] = xsave[i][k];
}

/* ---------------------------------------------------------------------- */

double FixPEJump::node_cost()
{
  return sampler->fraction(sample_mask);
}

/* ----------------------------------------------------------------------
   before moving: the positions where forces are evaluated in this step lie
   on the segments x + t v^{n+1/2}, t in [lo, hi], so the neighbor lists stay
   valid for all of them if the ends are within half the skin of the
   positions of the last build; otherwise request a rebuild at this step.
   Atoms with select[i] != 0 (the slow atoms of pe_jump/async) take steps of
   size hsel and are also evaluated for t in [lo2, hi2] (the coarse nodes),
   a span that a rebuild at the primary node must cover as well.
   Also catch the unbounded growth of the momentum jumps that marks a time
   step beyond the stability limit.
------------------------------------------------------------------------- */

void FixPEJump::check_excursion(double lo, double hi, const int *select, double lo2, double hi2,
                                double hsel, const double *lag)
{
  double **x = atom->x;
  const int *mask = atom->mask;
  const int nlocal = atom->nlocal;
  const double cp = rule->node[rule->primary()] * h_step;
  // if forces are evaluated at the primary node only, the neighbor list
  // check of the Verlet loop itself covers them
  const bool primary_only = !select && (lo == cp) && (hi == cp);
  double **xhold = (neighbor->dist_check && !primary_only) ? neighbor->get_xhold() : nullptr;

  // excursion^2, step length^2, jump displacement^2, |[v]|^2, |v^{n+1/2}|^2
  double local[5] = {0.0, 0.0, 0.0, 0.0, 0.0};
  if (stats_valid && !select) {
    // the magnitudes were taken by final_integrate(); only the nodes'
    // excursions are left, and none if the Verlet loop checks the only node
    local[1] = h_step * h_step * stats[0];
    local[2] = h_step * h_step * stats[1];
    local[3] = stats[1];
    local[4] = stats[0];
    if (xhold) local[0] = node_excursion(xhold, lo, hi, nullptr);
  } else {
    for (int i = 0; i < nlocal; i++) {
      if (!(mask[i] & groupbit)) continue;
      const bool both = select && select[i];
      const double h = both ? hsel : h_step;
      const double late = lag ? lag[i] : 0.0;
      double vv = 0.0, jj = 0.0, d[4] = {0.0, 0.0, 0.0, 0.0};
      for (int k = 0; k < 3; k++) {
        vv += vhalf[i][k] * vhalf[i][k];
        jj += jump[i][k] * jump[i][k];
        if (xhold) {
          const double a = x[i][k] - xhold[i][k];
          const double ends[4] = {a + lo * vhalf[i][k], a + hi * vhalf[i][k],
                                  a + (lo2 + late) * vhalf[i][k], a + (hi2 + late) * vhalf[i][k]};
          for (int e = 0; e < (both ? 4 : 2); e++) d[e] += ends[e] * ends[e];
        }
      }
      double span = h;
      if (both) span = MAX(span, MAX(fabs(lo2 - cp), fabs(hi2 - cp)));
      double step = span * span * vv, jmp = h * h * jj;
      if (!std::isfinite(step) || !std::isfinite(jmp)) step = jmp = vv = jj = BLOWUP;
      local[0] = MAX(local[0], MAX(MAX(d[0], d[1]), MAX(d[2], d[3])));
      local[1] = MAX(local[1], step);
      local[2] = MAX(local[2], jmp);
      local[3] = MAX(local[3], jj);
      local[4] = MAX(local[4], vv);
    }
  }
  finish_check(local);
}

/* ----------------------------------------------------------------------
   largest squared distance from the positions of the last neighbor list
   build xhold of the nodes x + t v^{n+1/2}, t = lo and hi, of the owned
   atoms of the group (those listed in only, if given)
------------------------------------------------------------------------- */

double FixPEJump::node_excursion(double **xhold, double lo, double hi, const AtomList *only) const
{
  double **x = atom->x;
  double worst = 0.0;
  const auto excursion = [&](int i) {
    double dlo = 0.0, dhi = 0.0;
    for (int k = 0; k < 3; k++) {
      const double a = x[i][k] - xhold[i][k];
      dlo += (a + lo * vhalf[i][k]) * (a + lo * vhalf[i][k]);
      dhi += (a + hi * vhalf[i][k]) * (a + hi * vhalf[i][k]);
    }
    worst = MAX(worst, MAX(dlo, dhi));
  };
  for_atoms(only, excursion);
  return worst;
}

/* ----------------------------------------------------------------------
   local = largest excursion^2 from the last build positions (0 if not
   checked), step length^2, jump displacement^2 (h |[v]|)^2, |[v]|^2 and
   |v^{n+1/2}|^2 of the local atoms. The scheme is unstable if the jumps
   have grown by more than STOP_GROWTH since the first steps of the run, or
   by more than HINT_GROWTH while moving atoms (or their jumps) by more than
   half the skin; a large step that is stable only needs a larger skin.
   Otherwise request a rebuild where the nodes leave the skin.
------------------------------------------------------------------------- */

void FixPEJump::finish_check(const double *local)
{
  // the same reduction tells whether another fix changed a velocity: then
  // damp auto damps the parasitic mode from now on in this run
  double values[6] = {local[0], local[1], local[2],
                      local[3], local[4], static_cast<double>(impulse_local)};
  double global[6];
  MPI_Allreduce(values, global, 6, MPI_DOUBLE, MPI_MAX, world);
  impulse_local = 0;
  if ((global[5] > 0.0) && (damp_time < 0.0)) damping = 1;

  // reference magnitude: the largest jump or velocity at the start of the run
  // (at the first step where anything moves)
  if (jump_ref == 0.0) jump_ref = MAX(global[3], global[4]);
  const double growth = (jump_ref > 0.0) ? sqrt(global[3] / jump_ref) : 0.0;

  const double half_skin = 0.5 * neighbor->skin;
  const double limit = (half_skin > 0.0) ? half_skin * half_skin : BLOWUP;
  const bool large = (global[1] >= limit) || (global[2] >= limit);
  if ((growth >= STOP_GROWTH) || (large && (growth >= HINT_GROWTH))) {
    energies();
    error->all(FLERR,
               "Fix {} is unstable at step {}: the momentum jumps grew {:.3g}-fold since the "
               "start of the run (jump energy {:.8g}). {}",
               style, update->ntimestep, growth, cached[1], instability_advice());
  }
  if (global[1] >= limit)
    error->all(FLERR,
               "Fix {}: atoms move more than half the neighbor skin ({}) between the force "
               "evaluations of step {}: reduce the time step (or K) or increase the skin",
               style, neighbor->skin, update->ntimestep);
  if (global[0] > limit) next_reneighbor = update->ntimestep;
}

/* ---------------------------------------------------------------------- */

bool FixPEJump::can_reverse() const
{
  return true;
}

/* ---------------------------------------------------------------------- */

std::string FixPEJump::instability_advice() const
{
  return fmt::format(
      "The time step {} is beyond the stability limit of the fastest motion (for "
      "masses m joined by springs of stiffness k in a chain, dt < sqrt(m/k); "
      "bond_style harmonic has k = 2K): {}",
      h_step, adapt ? "lower the adapt dtmin or eps" : "reduce it, or use the adapt keyword");
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

void FixPEJump::choose_next_dt()
{
  double **v = atom->v;
  const double *rmass = atom->rmass;
  const double *mass = atom->mass;
  const int *type = atom->type;
  const int *mask = atom->mask;
  const int nlocal = atom->nlocal;
  const double h = update->dt;
  const bool extrapolate = (hlast2 > 0.0);    // fhist2 holds the previous step's average
  const double c1 = extrapolate ? h / (h + hlast2) : 0.0;
  const double c2 = extrapolate ? 1.0 / (h + hlast2) : 0.0;

  // sum m of: P.P, P.Q, Q.Q, P.J, Q.J, J.J, v.v
  double local[7] = {0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0};
  for (int i = 0; i < nlocal; i++) {
    if (!(mask[i] & groupbit)) continue;
    const double m = rmass ? rmass[i] : mass[type[i]];
    for (int k = 0; k < 3; k++) {
      const double a = force->ftm2v * fsum[i][k] / m;
      const double da = extrapolate ? a - force->ftm2v * fhist2[i][k] / m : 0.0;
      const double P = 2.0 * (a + c1 * da), Q = 2.0 * c2 * da, J = jump[i][k];
      local[0] += m * P * P;
      local[1] += m * P * Q;
      local[2] += m * Q * Q;
      local[3] += m * P * J;
      local[4] += m * Q * J;
      local[5] += m * J * J;
      local[6] += m * v[i][k] * v[i][k];
    }
  }
  double sum[7];
  MPI_Allreduce(local, sum, 7, MPI_DOUBLE, MPI_SUM, world);

  const double mvv2e = force->mvv2e;
  const double scale = MAX(energy_scale, 0.5 * mvv2e * sum[6]);
  const double target = 8.0 * ADAPT_SAFETY * adapt_eps * scale / mvv2e;
  const auto jump8 = [&sum](double t) {    // 8/mvv2e times the predicted jump energy
    return t * t * sum[0] + 2.0 * t * t * t * sum[1] + t * t * t * t * sum[2] - 2.0 * t * sum[3] -
        2.0 * t * t * sum[4] + sum[5];
  };
  const double hcap = MIN(adapt_dtmax, ADAPT_GROWTH * h);
  const double hlow = MIN(adapt_dtmin, hcap);

  // largest step meeting the bound: scan down from hcap, then bisect
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
  hnew = MAX(hnew, adapt_dtmin);
  if (hnew != update->dt) set_timestep(hnew);
}

/* ----------------------------------------------------------------------
   change the time step the way fix dt/reset does
------------------------------------------------------------------------- */

void FixPEJump::set_timestep(double dt)
{
  update->update_time();
  update->dt = dt;
  update->dt_default = 0;
  if (force->pair) force->pair->reset_dt();
  for (auto &ifix : modify->get_fix_list()) ifix->reset_dt();
  output->reset_dt();
}

/* ----------------------------------------------------------------------
   0: velocities are the node velocities this fix left, 1: all of them were
   reversed (continue backwards in time: v^{1/2} -> -v^{-1/2}, same jump),
   2: changed otherwise
------------------------------------------------------------------------- */

int FixPEJump::detect_velocity_change()
{
  double **v = atom->v;
  const int *mask = atom->mask;
  const int nlocal = atom->nlocal;

  int local[2] = {0, 0};    // some differ, some are not reversed
  for (int i = 0; i < nlocal; i++) {
    if (!(mask[i] & groupbit)) continue;
    for (int k = 0; k < 3; k++) {
      const double vnode = vhalf[i][k] - 0.5 * jump[i][k];
      if (v[i][k] != vnode) local[0] = 1;
      if (v[i][k] != -vnode) local[1] = 1;
    }
  }
  int global[2];
  MPI_Allreduce(local, global, 2, MPI_INT, MPI_MAX, world);
  if (!global[0]) return 0;
  if (global[1] || !can_reverse()) return 2;

  for (int i = 0; i < nlocal; i++) {
    if (!(mask[i] & groupbit)) continue;
    for (int k = 0; k < 3; k++) {
      vhalf[i][k] = jump[i][k] - vhalf[i][k];
      v[i][k] = vhalf[i][k] - 0.5 * jump[i][k];
    }
  }
  cached_step = -1;
  return 1;
}

/* ----------------------------------------------------------------------
   pseudo-energy V(q^n) + pseudo-kinetic energy at the current positions;
   evaluates the energy once (used at setup for the adapt normalisation)
------------------------------------------------------------------------- */

double FixPEJump::pseudo_energy_now()
{
  double pe = potential_now(ForceSampler::ALL);
  if (force->pair && force->pair->tail_flag) {
    const double volume = domain->xprd * domain->yprd * domain->zprd;
    pe += force->pair->etail / volume;
  }
  energies();
  return pe + cached[0];
}

/* ----------------------------------------------------------------------
   potential energy of the contributions in mask at the current positions
   (one evaluation; the forces are left as they were)
------------------------------------------------------------------------- */

double FixPEJump::potential_now(int mask)
{
  grow_work();
  const int nlocal = atom->nlocal;
  if (nlocal) memcpy(&fsave[0][0], &atom->f[0][0], 3 * sizeof(double) * nlocal);
  sampler->compute(mask, ENERGY_GLOBAL, 0);
  if (nlocal) memcpy(&atom->f[0][0], &fsave[0][0], 3 * sizeof(double) * nlocal);
  return sampler->energy(mask);
}

/* ----------------------------------------------------------------------
   pseudo-kinetic energy (1/2) sum m v^{n-1/2}.v^{n+1/2} and jump energy
   (1/8) sum m |[v]^n|^2 of the fix group
------------------------------------------------------------------------- */

void FixPEJump::energies()
{
  if (cached_step == update->ntimestep) return;

  const double *rmass = atom->rmass;
  const double *mass = atom->mass;
  const int *type = atom->type;
  const int *mask = atom->mask;
  const int nlocal = atom->nlocal;

  double local[2] = {0.0, 0.0};
  for (int i = 0; i < nlocal; i++) {
    if (!(mask[i] & groupbit)) continue;
    const double m = rmass ? rmass[i] : mass[type[i]];
    for (int k = 0; k < 3; k++) {
      local[0] += m * (vhalf[i][k] - jump[i][k]) * vhalf[i][k];
      local[1] += m * jump[i][k] * jump[i][k];
    }
  }
  MPI_Allreduce(local, cached, 2, MPI_DOUBLE, MPI_SUM, world);
  cached[0] *= 0.5 * force->mvv2e;
  cached[1] *= 0.125 * force->mvv2e;
  cached_step = update->ntimestep;
}

/* ---------------------------------------------------------------------- */

double FixPEJump::compute_scalar()
{
  return compute_vector(0);
}

/* ---------------------------------------------------------------------- */

double FixPEJump::compute_vector(int n)
{
  switch (n) {
    case 0:
    case 1:
      energies();
      return cached[n];
    case 2:
      return update->dt;
    case 3:
      return evals_step;
    case 4:
      return evals_total;
  }
  return 0.0;
}

/* ---------------------------------------------------------------------- */

void FixPEJump::grow_work()
{
  if (nmax_work >= atom->nmax) return;
  nmax_work = atom->nmax;
  memory->destroy(fsum);
  memory->destroy(fsample);
  memory->destroy(xsave);
  memory->destroy(fsave);
  memory->create(fsum, nmax_work, 3, "pe_jump:fsum");
  memory->create(fsample, nmax_work, 3, "pe_jump:fsample");
  memory->create(xsave, nmax_work, 3, "pe_jump:xsave");
  memory->create(fsave, nmax_work, 3, "pe_jump:fsave");
  if (auto_tol > 0.0) {
    memory->destroy(fnode);
    memory->create(fnode, nmax_work, 3, "pe_jump:fnode");
  }
}

/* ---------------------------------------------------------------------- */

void FixPEJump::grow_arrays(int nmax)
{
  memory->grow(vhalf, nmax, 3, "pe_jump:vhalf");
  memory->grow(jump, nmax, 3, "pe_jump:jump");
  if (rule->has_end_nodes()) memory->grow(fstart, nmax, 3, "pe_jump:fstart");
  if (adapt || compensate) {
    memory->grow(fhist1, nmax, 3, "pe_jump:fhist1");
    memory->grow(fhist2, nmax, 3, "pe_jump:fhist2");
  }
}

/* ---------------------------------------------------------------------- */

void FixPEJump::copy_arrays(int i, int j, int /*delflag*/)
{
  for (int k = 0; k < 3; k++) {
    vhalf[j][k] = vhalf[i][k];
    jump[j][k] = jump[i][k];
    if (fstart) fstart[j][k] = fstart[i][k];
    if (fhist1) {
      fhist1[j][k] = fhist1[i][k];
      fhist2[j][k] = fhist2[i][k];
    }
  }
}

/* ----------------------------------------------------------------------
   an atom created during the simulation (fix deposit, create_atoms) starts
   with its velocity as free-flight and node velocity and no jump; its
   start-node force is taken at its first force evaluation (NaN until then)
------------------------------------------------------------------------- */

void FixPEJump::set_arrays(int i)
{
  for (int k = 0; k < 3; k++) {
    vhalf[i][k] = atom->v[i][k];
    jump[i][k] = 0.0;
    if (fstart) fstart[i][k] = std::nan("");
    if (fhist1) fhist1[i][k] = fhist2[i][k] = 0.0;
  }
  fresh_atoms = 1;
}

/* ---------------------------------------------------------------------- */

int FixPEJump::pack_exchange(int i, double *buf)
{
  int m = 0;
  for (int k = 0; k < 3; k++) buf[m++] = vhalf[i][k];
  for (int k = 0; k < 3; k++) buf[m++] = jump[i][k];
  if (fstart)
    for (int k = 0; k < 3; k++) buf[m++] = fstart[i][k];
  if (fhist1) {
    for (int k = 0; k < 3; k++) buf[m++] = fhist1[i][k];
    for (int k = 0; k < 3; k++) buf[m++] = fhist2[i][k];
  }
  return m;
}

/* ---------------------------------------------------------------------- */

int FixPEJump::unpack_exchange(int nlocal, double *buf)
{
  int m = 0;
  for (int k = 0; k < 3; k++) vhalf[nlocal][k] = buf[m++];
  for (int k = 0; k < 3; k++) jump[nlocal][k] = buf[m++];
  if (fstart)
    for (int k = 0; k < 3; k++) fstart[nlocal][k] = buf[m++];
  if (fhist1) {
    for (int k = 0; k < 3; k++) fhist1[nlocal][k] = buf[m++];
    for (int k = 0; k < 3; k++) fhist2[nlocal][k] = buf[m++];
  }
  return m;
}

/* ----------------------------------------------------------------------
   global state: whether the two-step scheme runs, with which rule
------------------------------------------------------------------------- */

void FixPEJump::write_restart(FILE *fp)
{
  double list[NGLOBAL];
  global_state(list);
  if (comm->me == 0) {
    int size = sizeof(list);
    fwrite(&size, sizeof(int), 1, fp);
    fwrite(list, sizeof(double), NGLOBAL, fp);
  }
}

/* ---------------------------------------------------------------------- */

void FixPEJump::global_state(double *list) const
{
  list[0] = started;
  list[1] = rule->family();
  list[2] = rule->points();
  list[3] = evals_total;
  list[4] = hlast;
  list[5] = hlast2;
}

/* ---------------------------------------------------------------------- */

void FixPEJump::restart(char *buf)
{
  auto *list = reinterpret_cast<double *>(buf);
  const bool same_rule = (static_cast<int>(list[1]) == rule->family()) &&
      (static_cast<int>(list[2]) == rule->points());
  started = (static_cast<int>(list[0]) != 0) && same_rule;
  evals_total = list[3];
  hlast = list[4];
  hlast2 = list[5];
  if (!same_rule && (comm->me == 0))
    utils::logmesg(lmp,
                   "Fix {}: quadrature differs from the restart file: the two-step scheme "
                   "restarts from the current state\n",
                   style);
}

/* ---------------------------------------------------------------------- */

int FixPEJump::pack_restart(int i, double *buf)
{
  buf[0] = nstate + 1;
  pack_exchange(i, &buf[1]);
  return nstate + 1;
}

/* ---------------------------------------------------------------------- */

void FixPEJump::unpack_restart(int nlocal, int nth)
{
  double **extra = atom->extra;
  int m = 0;
  for (int i = 0; i < nth; i++) m += static_cast<int>(extra[nlocal][m]);
  if (static_cast<int>(extra[nlocal][m]) != nstate + 1) {
    started = 0;
    return;
  }
  unpack_exchange(nlocal, &extra[nlocal][m + 1]);
}

/* ---------------------------------------------------------------------- */

int FixPEJump::size_restart(int /*nlocal*/)
{
  return nstate + 1;
}

/* ---------------------------------------------------------------------- */

int FixPEJump::maxsize_restart()
{
  return nstate + 1;
}

/* ----------------------------------------------------------------------
   reverse communication of the force field part copied before the Verlet
   loop's own reverse communication
------------------------------------------------------------------------- */

int FixPEJump::pack_reverse_comm(int n, int first, double *buf)
{
  int m = 0;
  for (int i = first; i < first + n; i++) {
    buf[m++] = fsample[i][0];
    buf[m++] = fsample[i][1];
    buf[m++] = fsample[i][2];
  }
  return m;
}

/* ---------------------------------------------------------------------- */

void FixPEJump::unpack_reverse_comm(int n, int *list, double *buf)
{
  int m = 0;
  for (int i = 0; i < n; i++) {
    const int j = list[i];
    fsample[j][0] += buf[m++];
    fsample[j][1] += buf[m++];
    fsample[j][2] += buf[m++];
  }
}

/* ---------------------------------------------------------------------- */

double FixPEJump::memory_usage()
{
  double bytes =
      (double) atom->nmax * 3 * sizeof(double) * (2 + (fstart ? 1 : 0) + (fhist1 ? 2 : 0));
  bytes += (double) nmax_work * 3 * sizeof(double) * 4;
  return bytes;
}
