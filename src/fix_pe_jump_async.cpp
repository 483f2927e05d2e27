/* ----------------------------------------------------------
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
   Asynchronous (slow/mixed/fast) version of the pseudo-energy conserving
   scheme, section 4 of: F. Marazzato, A. Ern, C. Mariotti, L. Monasse,
   Comput. Methods Appl. Mech. Engrg. 347 (2019) 906-927.

   Every LAMMPS time step is a coarse step h_S, as the outer step of
   run_style respa; it holds K fine steps h_F = h_S / K. Atoms of the fast
   group move and jump on every fine step with the forces of the FINE
   interactions (those involving a fast-group atom), which the fix
   evaluates itself. Slow atoms move in free flight over the coarse step;
   the fine interactions they take part in (mixed-slow) are integrated
   over each fine step and summed, the COARSE interactions (slow-slow) are
   integrated at the coarse quadrature nodes, one of which is the MD
   step's own force evaluation, and the slow atoms jump at the end of the
   coarse step. The MD step (list builds, communication of all ghosts,
   other fixes, output) thus sees every atom at one time: at the primary
   coarse node during the force evaluation, at the coarse node q^{n+1}
   at its end.
------------------------------------------------------------------------- */

#include "fix_pe_jump_async.h"

#include "atom.h"
#include "bond.h"
#include "comm.h"
#include "domain.h"
#include "error.h"
#include "force.h"
#include "group.h"
#include "input.h"
#include "modify.h"
#include "neighbor.h"
#include "pair.h"
#include "pe_jump_atom_state.h"
#include "pe_jump_centre_velocity.h"
#include "pe_jump_clock_assignment.h"
#include "pe_jump_errors.h"
#include "pe_jump_force_sampler.h"
#include "pe_jump_growth_watch.h"
#include "pe_jump_interaction_split.h"
#include "pe_jump_moving_ghosts.h"
#include "pe_jump_node_sampler.h"
#include "pe_jump_options.h"
#include "pe_jump_other_fixes.h"
#include "pe_jump_parasitic_damping.h"
#include "pe_jump_quadrature.h"
#include "pe_jump_split_tally.h"
#include "pe_jump_stability_guard.h"
#include "pe_jump_two_clocks.h"
#include "pe_jump_two_step.h"
#include "pe_jump_work_forces.h"
#include "timer.h"
#include "update.h"

#include <cmath>
#include <cstring>

using namespace LAMMPS_NS;
using namespace FixConst;
using PEJump::AtomState;
using PEJump::CentreVelocity;
using PEJump::ClockAssignment;
using PEJump::flat;
using PEJump::ForceSampler;
using PEJump::InteractionSplit;
using PEJump::NodeSampler;
using PEJump::OtherFixes;
using PEJump::Quadrature;
using PEJump::StabilityGuard;
using PEJump::TwoClocks;

// nodes closer than this (in fine steps) are the same
static constexpr double SAME_NODE = 1.0e-9;
// the global restart values, in this order: the state bits (HEAD_*,
// DAMP_*), the layout's format, the rule, the evaluations so far, K, what
// the clock assignment keeps (the fast group seen, 2 values; the clocks, 3;
// the buffer's reach), the census of the last run's end
enum RestartValue {
  HEAD,
  FORMAT,
  FAMILY,
  POINTS,
  EVALS_TOTAL,
  NFINE,
  FAST_SEEN,
  CLOCKS = FAST_SEEN + 2,
  BUFFER_REACH = CLOCKS + 3,
  CENSUS
};
static constexpr int NGLOBAL = CENSUS + PEJump::TwoStep::NCENSUS;
static constexpr int RESTART_FORMAT = 20261206;
// the scheme had started; the fast group is dynamic
static constexpr int HEAD_STARTED = 1, HEAD_DYNAMIC = 8;
// the parasitic damping: damp auto damps since a velocity change, its
// per-atom fields follow the scheme's, and the last fine and coarse steps
// were damped (the fields are valid)
static constexpr int DAMP_KICKED = 32, DAMP_FIELDS = 64, DAMP_FINE = 128, DAMP_COARSE = 256;
// the clocks of the parasitic damping's history
static constexpr int FINE_CLOCK = 0, COARSE_CLOCK = 1;

/* ---------------------------------------------------------------------- */

FixPEJumpAsync::FixPEJumpAsync(LAMMPS *lmp, int narg, char **arg) :
    Fix(lmp, narg, arg), rule(nullptr), sampler(nullptr), node_sampler(nullptr), state(nullptr),
    two_step(nullptr), guard(nullptr), damping(nullptr), ghosts(nullptr), others(nullptr),
    tally(nullptr), split(nullptr), clocks(nullptr), clock_assignment(nullptr), classes(nullptr),
    work(nullptr), changes_seen(0), reverse_copy(false), builds_inside(0), impulse_at_start(false),
    impulse_pending(false)
{
  opts = new PEJump::Options;
  evals = new PEJump::Evaluations;
  if (narg < 5) utils::missing_cmd_args(FLERR, "fix pe_jump/async", error);
  opts->parse(lmp, style, narg, arg, 5, true);
  const int nfine = utils::inumeric(FLERR, arg[3], false, lmp);
  if (nfine < 1) error->all(FLERR, "Fix pe_jump/async needs K >= 1 fine steps per coarse step");
  if (group->dynamic[igroup])
    error->all(FLERR,
               "Fix pe_jump/async does not allow a dynamic fix group ({}): the fast group may "
               "be dynamic, the fix group must not{}",
               group->names[igroup], PEJump::errorurl(56));
  if (group->find(arg[4]) < 0)
    error->all(FLERR, "Fix pe_jump/async fast group {} does not exist{}", arg[4],
               PEJump::errorurl(57));
  refuse_keywords();

  rule = new Quadrature(static_cast<Quadrature::Family>(opts->family), opts->npoints);
  sampler = new ForceSampler(lmp);
  node_sampler = new NodeSampler(lmp, sampler);
  guard = new StabilityGuard(lmp);
  others = new OtherFixes(lmp, this);
  tally = new PEJump::SplitTally(lmp);
  growth = new PEJump::GrowthWatch();
  work = new PEJump::WorkForces(lmp, 3);
  state = new AtomState(lmp);
  two_step = new PEJump::TwoStep(lmp, *state, rule->reuses_start_node());
  field.facc = state->add("facc", 3, 0.0);
  field.fstart_coarse = rule->reuses_start_node() ? state->add("fstart_coarse", 3, 0.0) : -1;
  field.end_impulse = rule->has_end_nodes() ? state->add("end_impulse", 3, 0.0) : -1;
  field.half_impulse = rule->has_end_nodes() ? -1 : state->add("half_impulse", 3, 0.0);
  field.fcoarse = state->add("fcoarse", 3, 0.0);
  damping = new PEJump::ParasiticDamping(*state);
  ghosts = new PEJump::MovingGhosts(lmp, this);
  clock_assignment = new ClockAssignment(
      lmp, this, arg[4], {opts->buffer_layers, opts->buffer_reach}, opts->fast_auto > 0.0);
  classes = new PEJump::ClockClasses(lmp, *state);
  clocks = new TwoClocks(nfine);
  split = new InteractionSplit(lmp, groupbit, clock_assignment->clock_bit());

  time_integrate = 1;
  scalar_flag = 1;
  vector_flag = 1;
  size_vector = 9;
  global_freq = 1;
  extscalar = 1;
  extvector = -1;
  extlist = new int[size_vector]{1, 1, 0, 0, 0, 0, 0, 0, 0};
  peratom_flag = 1;
  size_peratom_cols = 0;
  peratom_freq = 1;
  restart_global = 1;
  restart_peratom = 1;
  create_attribute = 1;
  comm_forward = 3;    // (the positions of MovingGhosts; the clock flags need 1)
  comm_reverse = 3;
  force_reneighbor = 1;
  next_reneighbor = -1;

  for (int i = 0; i < atom->nlocal; i++) FixPEJumpAsync::set_arrays(i);
  atom->add_callback(Atom::GROW);
  atom->add_callback(Atom::RESTART);
}

/* ---------------------------------------------------------------------- */

FixPEJumpAsync::~FixPEJumpAsync()
{
  if (modify->get_fix_by_id(id)) {
    atom->delete_callback(id, Atom::GROW);
    atom->delete_callback(id, Atom::RESTART);
  }
  if (clock_assignment) clock_assignment->delete_clock_group();
  delete evals;
  delete opts;
  delete[] extlist;
  delete split;
  delete clocks;
  delete classes;
  delete clock_assignment;
  delete ghosts;
  delete damping;
  delete two_step;
  delete state;
  delete work;
  delete tally;
  delete growth;
  delete others;
  delete guard;
  delete node_sampler;
  delete sampler;
  delete rule;
}

/* ---------------------------------------------------------------------- */

void FixPEJumpAsync::init()
{
  two_step->init(style);
  guard->refuse_zero_skin(style, false, "the coarse clock");
  others->sort(*sampler);
  sampler->refuse_accelerators(style);
  sampler->refuse_velocity_forces(style, rule->name(), false);
  refuse_unsplittable();
  refuse_other_fixes();
  node_sampler->refuse_step_end_side_effects(
      style, "on steps that tally energy the fine interactions are evaluated twice");
  // the lists of the fine interactions and those of the slow atoms are
  // both taken from LAMMPS' lists
  if (neighbor->includegroup)
    error->all(FLERR,
               "Fix {} does not support neigh_modify include: the neighbor lists must hold the "
               "pairs of every atom{}",
               style, PEJump::errorurl(6));
  const bool primary_at_end = (rule->node[rule->primary()] == 1.0);
  others->refuse_for_rule(rule->name(), primary_at_end, rule->only_end_nodes());
  others->warn_step_number(rule->name(), primary_at_end, rule->only_end_nodes());
  others->warn_energy_inside_step(rule->name(), primary_at_end);
  split->start_run();
  tally->init();
  clock_assignment->find_groups();
  split->set_fine_bit(clock_assignment->clock_bit());
  // thermostats drive the parasitic mode on both clocks (see fix pe_jump;
  // auto: over AUTO_STEPS coarse steps)
  damping->init(opts->damp_time, update->dt, (others->thermostats() > 0) && !rule->only_end_nodes(),
                others->thermostat_forces() > 0);
  maxexchange = state->values();
}

/* ----------------------------------------------------------------------
   the interactions split for the clocks, the atoms sorted by what they do
   on fine steps, and the ghost copies told which atoms move on them
------------------------------------------------------------------------- */

void FixPEJumpAsync::sort_by_clock()
{
  split->build();
  clock_assignment->find_slow(*split);
  clock_assignment->find_moving(*split);
  if (ghosts->usable()) ghosts->mark(clock_assignment->moving());
}

/* ----------------------------------------------------------------------
   the lists were rebuilt (every atom at the same time): split them again
------------------------------------------------------------------------- */

void FixPEJumpAsync::post_neighbor()
{
  split->check_topology();
  sort_by_clock();
  // a slow atom outside fine interactions has no fine force: a Lobatto
  // start node of its fine steps, should it join one, is zero
  double **fstart = two_step->fstart();
  if (fstart)
    for (const int i : clock_assignment->slow_held)
      for (int k = 0; k < 3; k++) fstart[i][k] = 0.0;
}

/* ----------------------------------------------------------------------
   at the coarse node, as the coarse step begins: a velocity that another
   fix changed since the last step (a thermostat, fix momentum) changed
   the node velocity, and the free flight changes by as much (the jumps
   are kept); the second half of the Lobatto rules' impulse of the other
   fixes' forces at the node (velocity Verlet), given the same way
------------------------------------------------------------------------- */

void FixPEJumpAsync::node_impulses()
{
  // (a pass over the atoms, made only while damp auto waits for a change)
  if (damping->awaits_impulse() && watch(OtherFixes::BETWEEN_STEPS) &&
      two_step->any_changed(group_atoms()))
    damping->impulse_here();
  // (a pass over the atoms only if an impulse waits: other fixes added
  // forces at the last coarse node, or a restart file may carry one)
  if ((field.end_impulse < 0) || !impulse_pending) return;
  double **v = atom->v;
  double **pending = state->vec(field.end_impulse);
  if (impulse_at_start) {
    // (the first step of a new start: see start_scheme())
    double **f = atom->f;
    const double kick = 0.5 * update->dt * force->ftm2v;
    for (int i = 0; i < atom->nlocal; i++)
      for (int k = 0; k < 3; k++)
        pending[i][k] = kick * two_step->inverse_mass_of(i) * (f[i][k] + pending[i][k]);
    impulse_at_start = false;
  }
  group_atoms().each(atom->mask, atom->nlocal, [&](int i) {
    for (int k = 0; k < 3; k++) {
      v[i][k] += pending[i][k];
      pending[i][k] = 0.0;
    }
  });
  impulse_pending = false;
}

/* ----------------------------------------------------------------------
   inside the coarse step every atom of the group is inside its step
------------------------------------------------------------------------- */

PEJump::FreeFlight FixPEJumpAsync::free_flight() const
{
  return {atom->v, two_step->jump(), nullptr};
}

/* ---------------------------------------------------------------------- */

void FixPEJumpAsync::setup(int /*vflag*/)
{
  two_step->agree_on_started(group_atoms(), style, opts->compensate < 0,
                             node_sampler->tallied(true));
  // the buffer is assigned when the scheme starts, or again if the restart
  // file was written with other buffer layers
  state->ensure(atom->nlocal);
  if (clock_assignment->assign_buffer(two_step->has_started(), *split)) split->invalidate();
  // a run with "pre no" keeps the lists of the previous run: split them if
  // this fix has not seen them yet
  if (!split->up_to_date()) post_neighbor();
  refuse_pair_misfit();
  two_step->fresh = 0;
  changes_seen = 0;
  clock_assignment->warn_if_made_static();
  check_clocks();

  grow_work();
  guard->start_run(!watch(OtherFixes::BETWEEN_STEPS | OtherFixes::INSIDE_STEP) &&
                   !domain->box_change);
  growth->restart();
  evals->step = 0.0;
  if (!two_step->has_started())
    start_scheme(nullptr, true);
  else
    continue_scheme();
  // the next run compares the energy of the run's end
  node_sampler->ask_energy_at(update->laststep);
  if (!rule->only_end_nodes()) others->refuse_interactions(rule->name().c_str());
  slow_magnitudes();
  classes->label(*split, *clock_assignment, groupbit);
  log_steps();
  if (damping->automatic_on() && !two_step->reading_snapshots()) damping->note(lmp, style, false);
}

/* ----------------------------------------------------------------------
   the two time steps, at every run (timestep is the coarse step)
------------------------------------------------------------------------- */

void FixPEJumpAsync::log_steps() const
{
  if ((comm->me != 0) || two_step->reading_snapshots()) return;
  utils::logmesg(lmp,
                 "Fix {}: coarse step h_S = {:.8g} (the time step), fine step h_F = h_S/K = "
                 "{:.8g} (K = {})\n",
                 style, update->dt, update->dt / clocks->steps(), clocks->steps());
}

/* ----------------------------------------------------------------------
   the state carried over (earlier run, restart): velocities changed since
   restart the scheme; a reversal of all of them goes on backwards in time
------------------------------------------------------------------------- */

void FixPEJumpAsync::continue_scheme()
{
  const int change = two_step->velocity_change(group_atoms(), true);
  if (change == 2)
    start_scheme("velocities were changed since the last run: restarting the two-step scheme "
                 "from the current positions and velocities",
                 true);
  if ((change == 1) && (comm->me == 0))
    utils::logmesg(lmp, "Fix {}: all velocities were reversed: continuing backwards in time\n",
                   style);
}

/* ----------------------------------------------------------------------
   keywords of fix pe_jump that the fixed steps of the two clocks exclude
------------------------------------------------------------------------- */

void FixPEJumpAsync::refuse_keywords() const
{
  if (opts->adapt_eps > 0.0)
    error->all(FLERR,
               "Fix pe_jump/async does not support the adapt keyword: the coarse and fine "
               "steps are fixed");
  if (opts->auto_tol > 0.0)
    error->all(FLERR, "Fix pe_jump/async does not support quadrature auto: choose a fixed rule");
  if (opts->compensate > 0)
    error->all(FLERR, "Fix pe_jump/async does not support compensate yes: its steps are fixed");
  if (opts->sample_mask != ForceSampler::ALL)
    error->all(FLERR,
               "Fix pe_jump/async samples all force contributions: remove the sample keyword");
}

/* ----------------------------------------------------------------------
   with buffer layers the fine clock is a group of its own, kept with the
   atoms (and in restart files); init() looks it up
------------------------------------------------------------------------- */

void FixPEJumpAsync::post_constructor()
{
  clock_assignment->create_clock_group();
}

/* ---------------------------------------------------------------------- */

int FixPEJumpAsync::setmask()
{
  return INITIAL_INTEGRATE | POST_NEIGHBOR | PRE_FORCE | PRE_REVERSE | FINAL_INTEGRATE;
}

/* ----------------------------------------------------------------------
   force fields that cannot be split into fine and coarse interactions
------------------------------------------------------------------------- */

void FixPEJumpAsync::refuse_unsplittable() const
{
  if (force->pair && force->pair->manybody_flag)
    error->all(FLERR,
               "Fix pe_jump/async cannot split the many-body pair style {} into slow and fast "
               "interactions: use fix pe_jump{}",
               force->pair_style, PEJump::errorurl(47));
  if (force->kspace)
    error->all(FLERR,
               "Fix pe_jump/async cannot split k-space ({}) into slow and fast interactions: "
               "use fix pe_jump{}",
               force->kspace_style, PEJump::errorurl(48));
  if (atom->peri_flag)
    error->all(FLERR,
               "Fix pe_jump/async cannot split peridynamic interactions (atom style {}): use fix "
               "pe_jump{}",
               atom->atom_style, PEJump::errorurl(49));
  // a bond style whose bonds can break (partial_flag) changes the topology
  // and may keep data per entry of the bond list, whose order the split
  // changes
  if (force->bond && force->bond->partial_flag && (atom->molecular != Atom::ATOMIC))
    error->all(FLERR,
               "Fix pe_jump/async cannot split bond style {}: its bonds can break, and the split "
               "reorders the bond list. Use fix pe_jump{}",
               force->bond_style, PEJump::errorurl(50));
}

/* ----------------------------------------------------------------------
   other fixes that integrate atoms, or act where the atoms are on two
   clocks: the fixes that act on the forces or velocities at coarse nodes
   (at the MD step's evaluation, at its end) are taken, see the sequence of
   a coarse step
------------------------------------------------------------------------- */

void FixPEJumpAsync::refuse_other_fixes() const
{
  // the interactions among atoms outside the fix group are evaluated only
  // at coarse nodes, for the slow atoms: nothing else may integrate them
  for (const auto &ifix : modify->get_fix_list())
    if ((ifix != this) && ifix->time_integrate)
      error->all(FLERR,
                 "Fix pe_jump/async must be the only time integration fix (found fix {} {}): "
                 "atoms outside its group are frozen scenery{}",
                 ifix->id, ifix->style, PEJump::errorurl(40));

  // a force field that changes during the run (fix adapt) would be sampled
  // at the fine and the coarse nodes at other times than theirs; fixes that
  // act in initial_integrate (fix recenter, fix tmd) take the atoms for
  // being at the step start, which the fine steps leave
  for (const auto &ifix : modify->get_fix_list()) {
    const bool adapts = utils::strmatch(ifix->style, "^adapt");
    if ((ifix != this) && !ifix->time_integrate &&
        (adapts || (ifix->setmask() & INITIAL_INTEGRATE)))
      error->all(FLERR,
                 "Fix pe_jump/async cannot yet be combined with fix {} ({}), which {}. Use fix "
                 "pe_jump{}",
                 ifix->id, ifix->style,
                 adapts ? "changes the force field during the run"
                        : "acts on the atoms in initial_integrate",
                 adapts ? PEJump::errorurl(41) : PEJump::errorurl(42));
  }
  // fix deform with remap v changes the velocity of an atom that crosses a
  // periodic boundary inside its step
  if (domain->deform_vremap)
    error->all(FLERR,
               "Fix pe_jump/async cannot yet be combined with fix deform with remap v, which "
               "changes velocities at periodic boundaries{}",
               PEJump::errorurl(43));

  // velocities reversed inside the step (at the primary coarse node, where
  // the atoms on the fine clock are inside a fine step), and atoms inserted
  // there, which have no state for the rest of the coarse step
  for (const auto &ifix : modify->get_fix_list()) {
    if (ifix == this) continue;
    if (OtherFixes::reverses_velocities(ifix))
      error->all(FLERR,
                 "Fix pe_jump/async cannot yet be combined with fix {} ({}), which reverses "
                 "velocities inside the coarse step{}",
                 ifix->id, ifix->style, PEJump::errorurl(44));
    if (OtherFixes::inserted_bits(ifix))
      error->all(FLERR,
                 "Fix pe_jump/async cannot yet be combined with fix {} ({}), which inserts atoms "
                 "inside the coarse step. Use fix pe_jump{}",
                 ifix->id, ifix->style, PEJump::errorurl(45));
  }
}

/* ---------------------------------------------------------------------- */

void FixPEJumpAsync::setup_post_neighbor()
{
  post_neighbor();
}

/* ----------------------------------------------------------------------
   the ranks agree whether another fix changed a velocity (global)
------------------------------------------------------------------------- */

void FixPEJumpAsync::refuse_velocity_changes()
{
  int any = 0;
  MPI_Allreduce(&changes_seen, &any, 1, MPI_INT, MPI_MAX, world);
  if (any)
    error->all(FLERR,
               "Fix pe_jump/async: another fix changed velocities inside the coarse step of step "
               "{}{}",
               update->ntimestep, PEJump::errorurl(46));
}

/* ----------------------------------------------------------------------
   pair styles whose forces the split cannot put on the clocks, as the
   probes of the split tell them at setup
------------------------------------------------------------------------- */

void FixPEJumpAsync::refuse_pair_misfit() const
{
  const auto fit = split->pair_fit();
  if (fit == InteractionSplit::OFF_LISTS)
    error->all(FLERR,
               "Fix pe_jump/async cannot split pair style {}: it computes forces that are not in "
               "its neighbor lists{}",
               force->pair_style, PEJump::errorurl(51));
  if (fit == InteractionSplit::OFF_PAIRS)
    error->all(FLERR,
               "Fix pe_jump/async cannot split pair style {}: the force of a pair acts on other "
               "atoms than the two of the pair{}",
               force->pair_style, PEJump::errorurl(52));
  if (fit == InteractionSplit::NOT_ADDITIVE)
    error->all(FLERR,
               "Fix pe_jump/async cannot split pair style {}: the force of two pairs of an atom is "
               "not the sum of the forces of each{}",
               force->pair_style, PEJump::errorurl(53));
  if (fit == InteractionSplit::ON_TIME)
    error->all(FLERR,
               "Fix pe_jump/async cannot take pair style {}: its forces depend on the time or the "
               "step. Use fix pe_jump{}",
               force->pair_style, PEJump::errorurl(54));
}

/* ----------------------------------------------------------------------
   an energy minimization moves the atoms and keeps the velocities: the
   next run restarts the scheme
------------------------------------------------------------------------- */

void FixPEJumpAsync::min_setup(int /*vflag*/)
{
  two_step->atoms_minimized();
}

/* ---------------------------------------------------------------------- */

void FixPEJumpAsync::setup_pre_reverse(int eflag, int vflag)
{
  pre_reverse(eflag, vflag);
}

/* ----------------------------------------------------------------------
   midpoint rule at a clock change: the forces at the node q^n of the atoms
   that change clock (rows of fnode; the work array of the coarse sum is
   free between coarse steps) without a complete evaluation. Every
   interaction of an atom on the fine clock is in the FINE subset, so its
   force from that subset is complete, summed in the same order. With the
   old clocks: rows of every atom on the fine clock (among them those who
   leave it); with the new ones (to_fine): rows of those who joined it.
   Returns the cost in evaluations
------------------------------------------------------------------------- */

double FixPEJumpAsync::fine_forces_at_node(double **fnode, const std::vector<int> *to_fine)
{
  const int nlocal = atom->nlocal;
  const auto wanted = [&](int i) {
    return to_fine ? ((*to_fine)[i] > 0) : (split->fine(i) != 0);
  };
  int local = 0, any = 0;
  for (int i = 0; i < nlocal && !local; i++) local = wanted(i) ? 1 : 0;
  MPI_Allreduce(&local, &any, 1, MPI_INT, MPI_MAX, world);
  if (!any) return 0.0;

  NodeSampler::Keep keep(*node_sampler);
  split->activate(InteractionSplit::FINE);
  sampler->compute(ForceSampler::ALL, 0, 0);
  split->restore();
  double **f = atom->f;
  for (int i = 0; i < nlocal; i++)
    if (wanted(i))
      for (int k = 0; k < 3; k++) fnode[i][k] = f[i][k];
  return split->fraction(InteractionSplit::FINE);
}

/* ----------------------------------------------------------------------
   Lobatto start nodes at q^0: the fine interactions for every atom, the
   slow interactions for the slow atoms
------------------------------------------------------------------------- */

void FixPEJumpAsync::store_start_node()
{
  double **f = atom->f;
  double **fstart = two_step->fstart();
  double **fstart_coarse = state->vec(field.fstart_coarse);
  const int *mask = atom->mask;
  const int nlocal = atom->nlocal;
  NodeSampler::Keep keep(*node_sampler);

  split->activate(InteractionSplit::FINE);
  sampler->compute(ForceSampler::ALL, 0, 0);
  for (int i = 0; i < nlocal; i++)
    if (mask[i] & groupbit)
      for (int k = 0; k < 3; k++) fstart[i][k] = f[i][k];

  split->activate(InteractionSplit::COARSE);
  sampler->compute(ForceSampler::ALL, 0, 0);
  for (int i = 0; i < nlocal; i++)
    for (int k = 0; k < 3; k++) fstart_coarse[i][k] = split->coarse(i) ? f[i][k] : 0.0;

  split->restore();
}

/* ---------------------------------------------------------------------- */

double FixPEJumpAsync::node_cost() const
{
  const auto which = split->active();
  return ((which == InteractionSplit::NONE) || (which == InteractionSplit::ALL))
      ? 1.0
      : split->fraction(which);
}

/* ---------------------------------------------------------------------- */

void FixPEJumpAsync::pre_reverse(int eflag, int vflag)
{
  split->restore();
  node_sampler->note_step_flags(eflag, vflag);
  if (tally->kept() && (eflag & ENERGY_GLOBAL)) tally->add();
  // the coarse interactions' forces, before other fixes add theirs
  if (!others->add_forces()) return;
  work->ensure(atom->nlocal + atom->nghost, needed_work() | (1 << COPY));
  const int nall = atom->nlocal + atom->nghost;
  if (nall) memcpy(&work->get(COPY)[0][0], &atom->f[0][0], 3 * sizeof(double) * nall);
}

/* ----------------------------------------------------------------------
   communication for the clock assignment: the fine clock of the ghost
   atoms (forward), flags set on ghosts (reverse); for the fine steps (the
   atoms that move on them, MovingGhosts); the coarse forces apart from
   other fixes' (reverse, COPY)
------------------------------------------------------------------------- */

int FixPEJumpAsync::pack_forward_comm(int n, int *list, double *buf, int pbc_flag, int *pbc)
{
  if (ghosts->active()) return ghosts->pack_forward(n, list, buf, pbc_flag, pbc);
  return clock_assignment->pack_forward(n, list, buf);
}

/* ---------------------------------------------------------------------- */

void FixPEJumpAsync::unpack_forward_comm(int n, int first, double *buf)
{
  if (ghosts->active())
    ghosts->unpack_forward(n, first, buf);
  else
    clock_assignment->unpack_forward(n, first, buf);
}

/* ---------------------------------------------------------------------- */

int FixPEJumpAsync::pack_reverse_comm(int n, int first, double *buf)
{
  if (ghosts->active()) return ghosts->pack_reverse(n, first, buf);
  if (!reverse_copy)
    return clock_assignment->reversing() ? clock_assignment->pack_reverse(n, first, buf) : 0;
  double **copy = work->get(COPY);
  int m = 0;
  for (int i = first; i < first + n; i++)
    for (int k = 0; k < 3; k++) buf[m++] = copy[i][k];
  return m;
}

/* ---------------------------------------------------------------------- */

void FixPEJumpAsync::unpack_reverse_comm(int n, int *list, double *buf)
{
  if (ghosts->active()) {
    ghosts->unpack_reverse(n, list, buf);
    return;
  }
  if (!reverse_copy) {
    if (clock_assignment->reversing()) clock_assignment->unpack_reverse(n, list, buf);
    return;
  }
  double **copy = work->get(COPY);
  int m = 0;
  for (int i = 0; i < n; i++)
    for (int k = 0; k < 3; k++) copy[list[i]][k] += buf[m++];
}

/* ----------------------------------------------------------------------
   the per-atom output (the classes) is a field of the state table, which
   may move when it grows
------------------------------------------------------------------------- */

void FixPEJumpAsync::show_classes()
{
  vector_atom = classes->classes();
}

/* ----------------------------------------------------------------------
   per-atom state: the table owns it and grows with the owned atoms
------------------------------------------------------------------------- */

void FixPEJumpAsync::grow_arrays(int /*nmax*/)
{
  state->ensure(atom->nlocal);
  show_classes();
}

/* ---------------------------------------------------------------------- */

void FixPEJumpAsync::copy_arrays(int i, int j, int /*delflag*/)
{
  state->copy(i, j);
  show_classes();
}

/* ----------------------------------------------------------------------
   an atom created during the simulation starts with its velocity and no
   jump (see fix pe_jump)
------------------------------------------------------------------------- */

void FixPEJumpAsync::set_arrays(int i)
{
  state->reset(i);
  two_step->mark(i);
  two_step->fresh = 1;
  show_classes();
}

/* ---------------------------------------------------------------------- */

int FixPEJumpAsync::pack_exchange(int i, double *buf)
{
  return state->pack(i, buf);
}

/* ---------------------------------------------------------------------- */

int FixPEJumpAsync::unpack_exchange(int nlocal, double *buf)
{
  const int m = state->unpack(nlocal, buf);
  show_classes();
  return m;
}

/* ---------------------------------------------------------------------- */

int FixPEJumpAsync::pack_restart(int i, double *buf)
{
  // written during a run: the velocities are the fix's own
  if (update->whichflag) two_step->mark(i);
  return state->pack_restart(i, buf);
}

/* ---------------------------------------------------------------------- */

void FixPEJumpAsync::unpack_restart(int nlocal, int nth)
{
  // a misfit is told by TwoStep::agree_on_started()
  if (!state->unpack_restart(nlocal, nth)) two_step->restart_data_unfit();
  show_classes();
}

/* ---------------------------------------------------------------------- */

int FixPEJumpAsync::size_restart(int /*nlocal*/)
{
  return state->restart_size();
}

/* ---------------------------------------------------------------------- */

int FixPEJumpAsync::maxsize_restart()
{
  return state->restart_size();
}

/* ---------------------------------------------------------------------- */

double FixPEJumpAsync::memory_usage()
{
  return state->memory_usage() + node_sampler->memory_usage() + work->memory_usage();
}

/* ---------------------------------------------------------------------- */

PEJump::AtomSet FixPEJumpAsync::group_atoms(const AtomList *only) const
{
  return {groupbit, only};
}

/* ---------------------------------------------------------------------- */

bool FixPEJumpAsync::watch(int when) const
{
  return others->may_change_velocities(when);
}

/* ---------------------------------------------------------------------- */

double FixPEJumpAsync::compute_scalar()
{
  return compute_vector(0);
}

/* ----------------------------------------------------------------------
   the coarse step begins at the coarse node q^n: the fine steps up to the
   primary coarse node, where every atom then is for the MD step's
   evaluation of the coarse interactions
------------------------------------------------------------------------- */

void FixPEJumpAsync::initial_integrate(int /*vflag*/)
{
  // (after write_restart or write_data between runs without setup the
  // ghost atoms were rebuilt: the fine steps need lists that fit them)
  const bool stale = two_step->awaits_setup() &&
      two_step->check_run_without_setup(style, group_atoms(), clock_assignment->changed());
  if (two_step->has_started()) change_clocks();
  node_impulses();
  step_now.lists_forced = guard->rebuild_forced();
  begin_coarse_step();
  // the step ends at the primary node (Lobatto rules): the fine and the
  // coarse interactions are evaluated there, and their tallies give the
  // energy output of the step without an evaluation of everything
  tally->expect(primary_is_last_node() && node_sampler->energy_only_step());
  if (stale) build_lists_now();
  const double primary = rule->node[rule->primary()];
  fine_steps_until(primary * clocks->steps());
  hold_until(primary * update->dt);
  // the MD step's evaluation is at the primary coarse node: a force that
  // depends on time (a variable of time, e.g. in fix addforce) must see the
  // node's time, or its impulse is off by h_S F'/2 per step (first order).
  // Put back as the MD step's evaluation is done
  step_now.end_time = update->atime;
  update->atime -= (1.0 - primary) * update->dt;
}

/* ----------------------------------------------------------------------
   every atom of the group begins its step: the slow atoms their coarse
   step, those on the fine clock their first fine step
------------------------------------------------------------------------- */

void FixPEJumpAsync::begin_coarse_step()
{
  clocks->begin(update->dt);
  evals->step = 0.0;
  step_now.speed2 = step_now.change = 0.0;
  grow_work();
  two_step->open(group_atoms(), watch(OtherFixes::INSIDE_STEP));
}

/* ----------------------------------------------------------------------
   the atoms that move on fine steps go on to u fine steps from the coarse
   step's start: whole fine steps, then free flight into the next
------------------------------------------------------------------------- */

void FixPEJumpAsync::fine_steps_until(double u)
{
  // a fine step followed by another whole one here moves its atoms on to
  // the next one's primary node in the same pass
  while (clocks->done() + 1 <= u + SAME_NODE) fine_step(clocks->done() + 2 <= u + SAME_NODE);
  if (u - clocks->done() > SAME_NODE) {
    const double into = (u - clocks->done()) * clocks->fine_step();
    move_moving(into - clocks->into());
    clocks->moved_to(u);
  }
}

/* ----------------------------------------------------------------------
   one fine step of the atoms that move on fine steps, from where they are
   in it: the fine interactions at its nodes, the jumps of the atoms on the
   fine clock, the fine impulse on the slow ones
------------------------------------------------------------------------- */

void FixPEJumpAsync::fine_step(bool next_ahead)
{
  const double h = clocks->fine_step();
  const double into = clocks->into();
  if (check_fine_nodes(into)) build_lists_now();

  // the evaluations clear and keep the forces of the atoms they act on only
  // (and communicate those atoms' ghost copies only)
  const ForceSampler::Touched moving{0, &clock_assignment->moving_atoms,
                                     ghosts->usable() ? ghosts : nullptr};
  split->activate(InteractionSplit::FINE);
  sampler->only_touch(&moving);
  const bool walk = walks_inner_nodes();
  const double at = walk ? walk_inner_nodes(into) : into;
  move_moving(rule->node[rule->primary()] * h - at);
  const bool at_end = tally->expected() && (clocks->done() + 1 == clocks->steps());
  sampler->compute(ForceSampler::ALL, at_end ? ENERGY_GLOBAL : 0, 0);
  if (at_end) tally->keep();
  evals->step += node_cost();
  if (rule->size() > 1) fine_quadrature_sum(walk);
  sampler->only_touch(nullptr);
  split->restore();

  double mag[2] = {0.0, 0.0};
  const double first = rule->node[walk ? rule->first_sampled() : rule->primary()];
  const double ahead = next_ahead ? first * h : -1.0;
  finish_fine_step((rule->size() > 1) ? work->get(SUM) : atom->f, ahead, mag);
  step_now.speed2 = MAX(step_now.speed2, mag[0]);
  step_now.change = MAX(step_now.change, mag[1]);
  guard->set_stats(step_now.speed2, step_now.change);
  clocks->fine_step_done();
  if (ahead > 0.0) clocks->moved_to(clocks->done() + first);
}

/* ----------------------------------------------------------------------
   a rule with end nodes and nodes between them (lobatto 3 and up): the
   atoms that move on fine steps go through the nodes between in order,
   from where they are in the step, before its primary node, the end
   (nothing to keep and put back); returns the time into the step where
   they then are
------------------------------------------------------------------------- */

bool FixPEJumpAsync::walks_inner_nodes() const
{
  return rule->has_end_nodes() && (rule->size() > 2);
}

/* ---------------------------------------------------------------------- */

double FixPEJumpAsync::walk_inner_nodes(double into)
{
  const AtomList &moving = clock_assignment->moving_atoms;
  const int last = rule->size() - 2;
  const int evaluated = node_sampler->walk_nodes(
      *rule, rule->first_sampled(), last, clocks->fine_step(), into, free_flight(),
      group_atoms(&moving), opts->sample_mask, work->get(SUM));
  evals->step += evaluated * node_cost();
  return rule->node[last] * clocks->fine_step();
}

/* ---------------------------------------------------------------------- */

void FixPEJumpAsync::move_moving(double dt)
{
  if (dt == 0.0) return;
  double *x = flat(atom->x);
  const double *v = flat(atom->v);
  for (const int i : clock_assignment->moving_atoms)
    for (int k = 3 * i; k < 3 * i + 3; k++) x[k] += dt * v[k];
}

/* ----------------------------------------------------------------------
   the slow atoms outside fine interactions wait where they are during the
   fine steps and move on by free flight where they are needed
------------------------------------------------------------------------- */

void FixPEJumpAsync::hold_until(double t)
{
  const double dt = t - clocks->held();
  double *x = flat(atom->x);
  const double *v = flat(atom->v);
  if (dt != 0.0)
    for (const int i : clock_assignment->slow_held)
      for (int k = 3 * i; k < 3 * i + 3; k++) x[k] += dt * v[k];
  clocks->hold_at(t);
}

/* ----------------------------------------------------------------------
   the nodes of a fine step, from where the moving atoms are (into the
   step): the stability guard, and their distances from the positions of
   the last list build, which LAMMPS checks only at the MD step
------------------------------------------------------------------------- */

bool FixPEJumpAsync::check_fine_nodes(double into)
{
  const double h = clocks->fine_step();
  const double lo = rule->node[rule->first_sampled()] * h - into;
  const double hi = rule->node.back() * h - into;
  double **xhold = neighbor->dist_check ? neighbor->get_xhold() : nullptr;
  double local[StabilityGuard::NMEASURES] = {0.0, 0.0, 0.0, 0.0, 0.0};
  guard->step(h);
  // speeds and jumps as the last fine step and coarse node left them (the
  // reference of the jumps' growth holds both clocks); distances only where
  // the moving atoms can have come near half the skin since they were last
  // measured
  guard->step_measures(group_atoms(&clock_assignment->moving_atoms), free_flight(),
                       two_step->jump(), xhold, {h, lo, hi}, local);
  guard->join_slow_stats(clocks->coarse_step(), local);
  // (with them, whether another fix changed a velocity at the coarse node:
  // damp auto damps the parasitic mode from then on)
  return guard->conclude(
      style, local, *damping,
      [&]() {
        return two_step->energies(group_atoms());
      },
      [&]() {
        return instability_advice();
      });
}

/* ----------------------------------------------------------------------
   inside the coarse step, where a fine step's nodes would leave half the
   skin: every atom to the time of the moving atoms, and the lists built
   there as the MD step builds them (Verlet::run(); LAMMPS offers no call
   for it). Atoms may change owner and order: what a coarse step keeps per
   atom is in the state table, which moves with them; nothing is inserted
   (no pre_exchange()) and the atoms are not sorted
------------------------------------------------------------------------- */

void FixPEJumpAsync::build_lists_now()
{
  hold_until(clocks->done() * clocks->fine_step() + clocks->into());
  if (domain->triclinic) domain->x2lamda(atom->nlocal);
  domain->pbc();
  if (domain->box_change) {
    domain->reset_box();
    comm->setup();
    if (neighbor->style) neighbor->setup_bins();
  }
  timer->stamp();
  comm->exchange();
  comm->borders();
  if (domain->triclinic) domain->lamda2x(atom->nlocal + atom->nghost);
  timer->stamp(Timer::COMM);
  if (modify->n_pre_neighbor) modify->pre_neighbor();
  neighbor->build(1);
  timer->stamp(Timer::NEIGH);
  if (modify->n_post_neighbor) modify->post_neighbor();
  grow_work();
  ++builds_inside;
}

/* ----------------------------------------------------------------------
   every interaction is evaluated at the step end (energy output, dumped
   forces), where no fine or coarse node was: the lists are built again
   there if an atom lies beyond half the skin
------------------------------------------------------------------------- */

void FixPEJumpAsync::lists_fit_step_end()
{
  double **xhold = neighbor->dist_check ? neighbor->get_xhold() : nullptr;
  if (!xhold) return;
  double **x = atom->x;
  double local = 0.0, worst = 0.0;
  group_atoms().each(atom->mask, atom->nlocal, [&](int i) {
    double d2 = 0.0;
    for (int k = 0; k < 3; k++) d2 += (x[i][k] - xhold[i][k]) * (x[i][k] - xhold[i][k]);
    local = MAX(local, d2);
  });
  MPI_Allreduce(&local, &worst, 1, MPI_DOUBLE, MPI_MAX, world);
  const double half_skin = 0.5 * neighbor->skin;
  if (worst > half_skin * half_skin) build_lists_now();
}

/* ----------------------------------------------------------------------
   the MD step evaluates the coarse interactions at the primary coarse node
------------------------------------------------------------------------- */

void FixPEJumpAsync::pre_force(int /*vflag*/)
{
  split->activate(InteractionSplit::COARSE);
  if (!shows_centre_velocities()) return;
  grow_work();    // (atoms may have come with the list build)
  CentreVelocity::show(group_atoms(), atom->mask, atom->nlocal, atom->v,
                       state->vec(field.half_impulse), work->get(VFREE));
}

/* ----------------------------------------------------------------------
   fsum = sum_k w_k F_fine(q_k) for the atoms that move on fine steps; the
   primary node p was evaluated (atom->f), a Lobatto start node is the
   previous fine step's end node; walked: the nodes between were summed
   (walk_inner_nodes())
------------------------------------------------------------------------- */

void FixPEJumpAsync::fine_quadrature_sum(bool walked)
{
  const int p = rule->primary();
  double **fsum = work->get(SUM);
  const AtomList &moving = clock_assignment->moving_atoms;

  const auto begin = rule->start_sum(walked);
  const double *f = flat(atom->f);
  double *sum = flat(fsum);
  double *start = rule->reuses_start_node() ? flat(two_step->fstart()) : nullptr;
  for (const int i : moving) begin(f + 3 * i, start ? start + 3 * i : nullptr, sum + 3 * i);
  const int first = rule->first_sampled();
  if (walked || (rule->size() - first <= 1)) return;
  const double h = clocks->fine_step();
  const int evaluated =
      node_sampler->sum_nodes(*rule, first, p, h, -rule->node[p] * h, free_flight(),
                              group_atoms(&moving), opts->sample_mask, fsum, nullptr, false);
  evals->step += evaluated * node_cost();
}

/* ----------------------------------------------------------------------
   forces of the fine interactions known (favg): the atoms on the fine
   clock jump and move on to the end of the fine step and begin the next
   inside the coarse step (moving on by ahead into it, if ahead >= 0); of
   the slow atoms those in a fine interaction move on as far and collect
   the fine impulse
------------------------------------------------------------------------- */

void FixPEJumpAsync::finish_fine_step(double **favg, double ahead, double *mag)
{
  const double h = clocks->fine_step();
  double **x = atom->x;
  double **v = atom->v;
  double **facc = state->vec(field.facc);
  const double rest = (1.0 - rule->node[rule->primary()]) * h;
  const bool more = clocks->done() + 1 < clocks->steps();
  const bool fingerprint =
      watch(more ? OtherFixes::INSIDE_STEP : (OtherFixes::BETWEEN_STEPS | OtherFixes::INSIDE_STEP));
  two_step->jump_loop(group_atoms(&clock_assignment->fast_atoms), favg,
                      {h, rest, more ? MAX(ahead, 0.0) : -1.0, fingerprint}, mag,
                      damping->step(h, FINE_CLOCK));
  damping->done(FINE_CLOCK);
  const double on = rest + MAX(ahead, 0.0);
  // (the slow atoms in fine interactions lie scattered among the others)
  double *xf = flat(x), *faccf = flat(facc);
  const double *vf = flat(v), *ff = flat(favg);
  for (const int i : clock_assignment->slow_moving)
    for (int k = 3 * i; k < 3 * i + 3; k++) {
      xf[k] += on * vf[k];
      faccf[k] += h * ff[k];
    }
}

/* ----------------------------------------------------------------------
   the coarse interactions at the primary coarse node are known: the rest
   of the fine steps, the other coarse nodes, then the slow atoms jump at
   the end of the coarse step, where every atom is
------------------------------------------------------------------------- */

void FixPEJumpAsync::final_integrate()
{
  update->atime = step_now.end_time;
  if (shows_centre_velocities())
    CentreVelocity::take_back(group_atoms(), atom->mask, atom->nlocal, atom->v,
                              state->vec(field.half_impulse), work->get(VFREE));
  grow_work();
  if (watch(OtherFixes::INSIDE_STEP)) {
    if (two_step->any_changed(group_atoms())) changes_seen = 1;
    refuse_velocity_changes();
  }
  evals->step += split->fraction(InteractionSplit::COARSE);
  double **fprimary = others->add_forces() ? coarse_forces_apart() : atom->f;
  const bool primary_last = primary_is_last_node();
  if (!primary_last) keep_coarse_primary(fprimary);
  fine_steps_until(clocks->steps());
  hold_until(update->dt);
  coarse_quadrature_sum();
  double mag[2] = {0.0, 0.0};
  slow_jumps(mag, primary_last ? fprimary : nullptr);
  guard->set_slow_stats(mag[0], mag[1]);
  if (impulse_pending) end_impulse_first_half();
  // lists that LAMMPS built in this step whatever the atoms did (neigh_modify
  // check no, a restart file written, a fix asking) are built again where a
  // run continued after this step builds them: every atom at the step end
  if (step_now.lists_forced && (neighbor->ago == 0)) build_lists_now();
  const bool tallied = tally->complete();
  if (node_sampler->step_end_evaluated(tallied)) lists_fit_step_end();

  split->activate(InteractionSplit::ALL);
  // no other time integrator (refuse_other_fixes()): no atoms to leave out
  const double at_end = node_sampler->at_step_end(others->step_observed(), 0, tallied);
  split->restore();
  if (tallied) add_fine_forces_at_end();
  evals->step += at_end;
  evals->total += evals->step;
  two_step->forget_energies();

  // the labels are output only: take them where something looks, when
  // at_step_end() has brought the ghosts to the node
  const bool ghosts_at_node = node_sampler->step_tallies() || others->step_observed();
  if (ghosts_at_node) classes->label(*split, *clock_assignment, groupbit);
  clock_assignment->evaluate_at_node(update->ntimestep, 1, ghosts_at_node);
  watch_growth();
}

/* ----------------------------------------------------------------------
   a fast group that stays the same: warn once per run if the jumps'
   share of the kinetic energy grows (a fast group that changes changes
   the share itself)
------------------------------------------------------------------------- */

void FixPEJumpAsync::watch_growth()
{
  if (clock_assignment->follows_group() || growth->growth() ||
      (update->ntimestep % PEJump::GrowthWatch::EVERY))
    return;
  double e[2];
  // (not the energies cached for output: fixes after this one may change v)
  two_step->energies_now(group_atoms(), e);
  growth->sample(e[0], e[1]);
  if (growth->growth() && (comm->me == 0))
    error->warning(FLERR,
                   "Fix {}: the jump energy's share of the kinetic energy grew from {:.3g} to "
                   "{:.3g} by step {}: a slow instability of the two clocks{}",
                   style, growth->reference_share(), growth->latest_share(), update->ntimestep,
                   PEJump::errorurl(66));
}

/* ----------------------------------------------------------------------
   the step's energy was tallied from the fine and the coarse evaluations
   at its end (SplitTally): the forces there are those of all interactions
   as after an evaluation of everything, for output that reads them (the
   fine ones of a Lobatto rule's end node are kept as the next fine step's
   start node)
------------------------------------------------------------------------- */

void FixPEJumpAsync::add_fine_forces_at_end()
{
  double **f = atom->f;
  double **fstart = two_step->fstart();
  for (const int i : clock_assignment->moving_atoms)
    for (int k = 0; k < 3; k++) f[i][k] += fstart[i][k];
}

/* ----------------------------------------------------------------------
   the slow atoms' coarse quadrature sum begins with the primary coarse
   node (the MD step's evaluation) and, for Lobatto rules, the start node;
   the primary node of a Lobatto rule is the next coarse step's start node
------------------------------------------------------------------------- */

void FixPEJumpAsync::keep_coarse_primary(double **f)
{
  double **fcoarse = state->vec(field.fcoarse);
  double **fstart = rule->reuses_start_node() ? state->vec(field.fstart_coarse) : nullptr;
  const auto begin = rule->start_sum();
  for (const int i : clock_assignment->slow_atoms)
    begin(f[i], fstart ? fstart[i] : nullptr, fcoarse[i]);
}

/* ----------------------------------------------------------------------
   other fixes added forces R to the coarse interactions' forces at the
   primary coarse node (kept apart in COPY, summed over the ghosts and
   acted on by the force-replacing fixes as the total was): every atom of
   the group gets the impulse h_S R/m there. Inside the coarse step (the
   midpoint and Legendre rules: position Verlet for these forces) on its
   free-flight velocity, which carries it on, half of it kept for the
   velocities that the other fixes see at the next primary node
   (field.half_impulse); at the end node (Lobatto rules: velocity Verlet)
   half on the node velocity there and half as the next coarse step begins
   (field.end_impulse). Returns the coarse interactions' forces.
------------------------------------------------------------------------- */

double **FixPEJumpAsync::coarse_forces_apart()
{
  grow_work();
  double **fcoarse = work->get(COPY);
  if (force->newton) {
    reverse_copy = true;
    comm->reverse_comm(this);
    reverse_copy = false;
  }
  const int nlocal = atom->nlocal;
  if (sampler->has_projections()) {
    NodeSampler::Keep keep(*node_sampler);
    if (nlocal) memcpy(&atom->f[0][0], &fcoarse[0][0], 3 * sizeof(double) * nlocal);
    sampler->project();
    if (nlocal) memcpy(&fcoarse[0][0], &atom->f[0][0], 3 * sizeof(double) * nlocal);
  }
  double **f = atom->f;
  double **v = atom->v;
  double **pending = (field.end_impulse >= 0) ? state->vec(field.end_impulse) : nullptr;
  double **half = (field.half_impulse >= 0) ? state->vec(field.half_impulse) : nullptr;
  impulse_pending = (pending != nullptr);
  const double kick = update->dt * force->ftm2v;
  group_atoms().each(atom->mask, nlocal, [&](int i) {
    const double scale = kick * two_step->inverse_mass_of(i);
    for (int k = 0; k < 3; k++) {
      const double dv = scale * (f[i][k] - fcoarse[i][k]);
      if (pending) {
        pending[i][k] = 0.5 * dv;
      } else {
        v[i][k] += dv;
        half[i][k] = 0.5 * dv;
      }
    }
  });
  return fcoarse;
}

/* ----------------------------------------------------------------------
   Lobatto rules: the first half of the impulse of the other fixes' forces
   on the node velocities at the end of the coarse step
------------------------------------------------------------------------- */

void FixPEJumpAsync::end_impulse_first_half()
{
  double **v = atom->v;
  double **pending = state->vec(field.end_impulse);
  const bool fingerprint = watch(OtherFixes::BETWEEN_STEPS | OtherFixes::INSIDE_STEP);
  group_atoms().each(atom->mask, atom->nlocal, [&](int i) {
    for (int k = 0; k < 3; k++) v[i][k] += pending[i][k];
    if (fingerprint) two_step->mark(i);
  });
}

/* ----------------------------------------------------------------------
   the other nodes of the coarse quadrature sum, q_S^n + c_k H v_S for the
   slow atoms, from their positions at the end of the coarse step
------------------------------------------------------------------------- */

void FixPEJumpAsync::coarse_quadrature_sum()
{
  const int first = rule->first_sampled();
  if (rule->size() - first <= 1) return;
  const double coarse = update->dt;
  // the slow atoms' nodes inside the coarse step, away from where LAMMPS
  // checked them (the primary node): lists built again at the step end
  // where one of them would leave half the skin
  double **xhold = neighbor->dist_check ? neighbor->get_xhold() : nullptr;
  if (xhold) {
    double local = guard->excursion(group_atoms(&clock_assignment->slow_atoms), free_flight(),
                                    xhold, (rule->node[first] - 1.0) * coarse, 0.0);
    double worst = 0.0;
    MPI_Allreduce(&local, &worst, 1, MPI_DOUBLE, MPI_MAX, world);
    const double half_skin = 0.5 * neighbor->skin;
    if (worst > half_skin * half_skin) build_lists_now();
  }
  split->activate(InteractionSplit::COARSE);
  const int evaluated =
      node_sampler->sum_nodes(*rule, first, rule->primary(), coarse, -coarse, free_flight(),
                              group_atoms(&clock_assignment->slow_atoms), opts->sample_mask,
                              state->vec(field.fcoarse), nullptr, false);
  evals->step += evaluated * node_cost();
  split->restore();
}

/* ----------------------------------------------------------------------
   true if nothing is evaluated between the primary coarse node and the
   slow atoms' jumps (lobatto 2: the primary node is the step end, which
   the fine steps reached before it, and there is no other coarse node to
   sample): the jumps read the primary node's forces where they are
------------------------------------------------------------------------- */

bool FixPEJumpAsync::primary_is_last_node() const
{
  const int first = rule->first_sampled();
  return (rule->node[rule->primary()] == 1.0) && (rule->size() - first <= 1);
}

/* ----------------------------------------------------------------------
   the slow atoms jump with the sums of their fine forces over the coarse
   step and the coarse quadrature sum (kept in field.fcoarse, or with fprimary
   the primary node's forces, see primary_is_last_node()); mag: their
   largest |v|^2, |[v]|^2
------------------------------------------------------------------------- */

void FixPEJumpAsync::slow_jumps(double *mag, double **fprimary)
{
  if (fprimary)
    slow_jumps_as<true>(mag, fprimary);
  else
    slow_jumps_as<false>(mag, state->vec(field.fcoarse));
}

/* ----------------------------------------------------------------------
   PRIMARY: fcoarse holds the primary node's forces, which begin the sum
   here as keep_coarse_primary() begins it (the same operations)
------------------------------------------------------------------------- */

template <bool PRIMARY> void FixPEJumpAsync::slow_jumps_as(double *mag, double **fcoarse)
{
  double **v = atom->v;
  double **jump = two_step->jump();
  double **facc = state->vec(field.facc);
  double **fstart = (PRIMARY && rule->reuses_start_node()) ? state->vec(field.fstart_coarse)
                                                           : nullptr;
  const auto begin = rule->start_sum();
  const double coarse = update->dt;
  const double kick = 2.0 * coarse * force->ftm2v;
  const bool fingerprint = watch(OtherFixes::BETWEEN_STEPS | OtherFixes::INSIDE_STEP);
  const PEJump::ParasiticDamping::Step *damp = damping->step(coarse, COARSE_CLOCK);
  // (the masses looked up here, the magnitudes kept in registers and the
  // fine impulses scaled by a product: this loop over the slow atoms is a
  // large part of a coarse step's own work)
  const double *rmass = atom->rmass;
  const double *minv = two_step->inverse_masses();
  const int *type = atom->type;
  const double per_time = 1.0 / coarse;
  double vv = mag[0], jj = mag[1];
  for (const int i : clock_assignment->slow_atoms) {
    double fslow[3], most[2] = {0.0, 0.0}, sum[3];
    const double *fc = fcoarse[i];
    if (PRIMARY) {
      begin(fcoarse[i], fstart ? fstart[i] : nullptr, sum);
      fc = sum;
    }
    for (int k = 0; k < 3; k++) {
      fslow[k] = facc[i][k] * per_time + fc[k];
      facc[i][k] = 0.0;
    }
    const double dtfm = kick * (rmass ? 1.0 / rmass[i] : minv[type[i]]);
    PEJump::TwoStep::jump_one(dtfm, fslow, v[i], jump[i], most, damp, i);
    vv = MAX(vv, most[0]);
    jj = MAX(jj, most[1]);
    if (fingerprint) two_step->mark(i);
  }
  mag[0] = vv;
  mag[1] = jj;
  damping->done(COARSE_CLOCK);
}

/* ----------------------------------------------------------------------
   largest |v|^2 and |[v]|^2 of the local slow atoms at a coarse node
------------------------------------------------------------------------- */

void FixPEJumpAsync::slow_magnitudes()
{
  double **v = atom->v;
  double **jump = two_step->jump();
  double most[2] = {0.0, 0.0};
  for (const int i : clock_assignment->slow_atoms) {
    double vv = 0.0, jj = 0.0;
    for (int k = 0; k < 3; k++) {
      const double vhalf = v[i][k] + 0.5 * jump[i][k];
      vv += vhalf * vhalf;
      jj += jump[i][k] * jump[i][k];
    }
    most[0] = MAX(most[0], vv);
    most[1] = MAX(most[1], jj);
  }
  guard->set_slow_stats(most[0], most[1]);
}

/* ----------------------------------------------------------------------
   a dynamic fast group or fast auto: atoms change clock at coarse nodes,
   where every atom is at its node q^n with its node velocity v^n, which it
   keeps. The interactions are split again and the atoms sorted by clock
   again; the atoms that changed restart their jumps with the kick of the
   new step (restart_jumps()), from the forces at q^n
------------------------------------------------------------------------- */

void FixPEJumpAsync::change_clocks()
{
  std::vector<int> to_fine, chosen;
  if (opts->fast_auto > 0.0)
    clock_assignment->choose_fast(opts->fast_auto, update->dt, clocks->steps(), two_step->jump(),
                                  chosen);
  const std::vector<int> *picked = chosen.empty() ? nullptr : &chosen;
  // (initial_integrate() of the step after the node)
  const bool due = clock_assignment->due(picked, update->ntimestep - 1, 1);
  // the midpoint rule takes the forces at the node from FINE subsets, the
  // first one of the old clocks (those who leave the fine clock), if two of
  // them cost less than a complete evaluation
  const bool by_subsets = due && !rule->has_end_nodes() && split->up_to_date() &&
      (split->fraction(InteractionSplit::FINE) < 0.5);
  if (by_subsets) {
    grow_work();
    evals->total += fine_forces_at_node(work->get(SUM), nullptr);
  }
  // the buffer layers are the partners within the cutoff at the node: the
  // ghost atoms must be there too (without energy output at the node they
  // are still where the last evaluation left them)
  if (due && (opts->buffer_layers > 0) && !by_subsets) comm->forward_comm();
  const bool changed = due && clock_assignment->follow(*split, to_fine, picked);
  if (due || !split->up_to_date()) sort_by_clock();
  if (!changed) return;
  // the forces at the node: with a Lobatto rule the start nodes of both
  // subsets are taken anew, and an atom's force is their sum (an
  // interaction of a fine-clock atom is a fine one), else the FINE subset
  // of the new clocks for those who join the fine clock
  if (rule->has_end_nodes()) {
    store_start_node();
    grow_work();
    double **total = work->get(SUM);
    double **fstart = two_step->fstart();
    double **fstart_coarse = state->vec(field.fstart_coarse);
    for (int i = 0; i < atom->nlocal; i++)
      for (int k = 0; k < 3; k++) total[i][k] = fstart[i][k] + fstart_coarse[i][k];
    restart_jumps(to_fine, total);
    evals->total += 1.0;
  } else if (by_subsets) {
    evals->total += fine_forces_at_node(work->get(SUM), &to_fine);
    restart_jumps(to_fine, work->get(SUM));
  } else {
    NodeSampler::Keep keep(*node_sampler);
    sampler->compute(ForceSampler::ALL, 0, 0);
    restart_jumps(to_fine, atom->f);
    evals->total += 1.0;
  }
  guard->forget_stats();
  slow_magnitudes();
  classes->label(*split, *clock_assignment, groupbit);
}

/* ----------------------------------------------------------------------
   the atoms that changed clock (to_fine[i] = 1: to the fine clock, -1: to
   the coarse clock) start their new clock with the initial kick of the
   scheme, [v]^n = h_new F(q^n)/m, with f the forces at the node (the
   smooth jump of the new step; whatever parasitic jump the old clock
   carried is dropped). Node velocities are untouched, and with them the
   momentum. The jumps are not shifted to keep sum m [v]: a common shift
   of the changed jumps is a parasitic jump of its own (for a single atom
   it undoes the restart), and atoms that change clock at every node
   pumped it up to a first-order error.
------------------------------------------------------------------------- */

void FixPEJumpAsync::restart_jumps(const std::vector<int> &to_fine, double **f)
{
  AtomList changed;
  for (int i = 0; i < atom->nlocal; i++)
    if (to_fine[i] && (atom->mask[i] & groupbit)) {
      changed.push_back(i);
      damping->forget(i);    // (its history is the other clock's)
    }
  const PEJump::AtomSet atoms = group_atoms(&changed);
  double before[2], after[2];
  two_step->energies_now(atoms, before);
  const double coarse = update->dt, fine = coarse / clocks->steps();
  two_step->start(atoms, f, 1.0, [&](int i) {
    return (to_fine[i] > 0) ? fine : coarse;
  });
  two_step->energies_now(atoms, after);
  // the pseudo-energy pe + (1/2) sum m v^{n-1/2}.v^{n+1/2} = pe + kinetic -
  // jump energy, with positions and node velocities kept
  clock_assignment->add_change_energy(
      before[1] - after[1],
      [&]() {
        double e[2];
        two_step->energies_now(group_atoms(), e);
        return e[0] + e[1];
      },
      style);
}

/* ----------------------------------------------------------------------
   (re)start the two-step scheme from the current positions, velocities and
   forces (see fix pe_jump); a slow atom's initial kick is over the coarse
   step
------------------------------------------------------------------------- */

void FixPEJumpAsync::start_scheme(const char *why, bool with_start)
{
  if (with_start) {
    double **facc = state->vec(field.facc);
    // (no impulse of other fixes before the first step)
    double **half = (field.half_impulse >= 0) ? state->vec(field.half_impulse) : nullptr;
    for (int i = 0; i < atom->nlocal; i++)
      for (int k = 0; k < 3; k++) {
        facc[i][k] = 0.0;
        if (half) half[i][k] = 0.0;
      }
  }
  if (why && (comm->me == 0)) utils::logmesg(lmp, "Fix {}: {}\n", style, why);
  grow_work();
  if (with_start && rule->reuses_start_node()) store_start_node();
  const double kick = (opts->init_style == PEJump::Options::KICK) ? 1.0 : 0.0;
  const double coarse = update->dt, fine = coarse / clocks->steps();
  const auto kick_with = [&](double **f) {
    two_step->start(group_atoms(), f, kick, [&](int i) {
      return split->coarse(i) ? coarse : fine;
    });
  };
  // the forces of the interactions (acted on by the force-replacing fixes)
  // without those that other fixes add: the setup's forces hold what the
  // fixes before this one did only
  if (others->add_forces() || sampler->has_projections()) {
    NodeSampler::Keep keep(*node_sampler);
    sampler->compute(ForceSampler::ALL, 0, 0);
    evals->total += 1.0;
    kick_with(atom->f);
    // Lobatto rules: the first coarse step begins with half the impulse of
    // the other fixes' forces at q^0, which all of them have added only
    // when the first step begins (those defined after this fix act after
    // its setup): the interactions' forces wait in field.end_impulse until then
    if (with_start && (field.end_impulse >= 0) && others->add_forces()) {
      double **pending = state->vec(field.end_impulse);
      double **f = atom->f;
      for (int i = 0; i < atom->nlocal; i++)
        for (int k = 0; k < 3; k++) pending[i][k] = -f[i][k];
      impulse_at_start = impulse_pending = true;
    }
  } else {
    kick_with(atom->f);
  }
  two_step->set_started(true);
  damping->forget_history();
  guard->forget_stats();
}

/* ---------------------------------------------------------------------- */

std::string FixPEJumpAsync::instability_advice() const
{
  return fmt::format("The fine step {} (fast and mixed atoms), the coarse step {} (slow atoms, the "
                     "time step), or their coupling at the interface is unstable: reduce the "
                     "time step or change K{}{}",
                     update->dt / clocks->steps(), update->dt,
                     opts->buffer_layers ? "" : ", or add the keyword buffer 1",
                     PEJump::errorurl(2));
}

/* ---------------------------------------------------------------------- */

double FixPEJumpAsync::compute_vector(int n)
{
  switch (n) {
    case 0:
    case 1:
      return two_step->energies(group_atoms())[n];
    case 2:
      return update->dt;
    case 3:
      return evals->step;
    case 4:
      return evals->total;
    case 5:
      return 1.0;    // every MD step ends at a coarse node
    case 6:
    case 7:
    case 8:
      return classes->count(n - 6);
  }
  return 0.0;
}

/* ----------------------------------------------------------------------
   global state: whether the two-step scheme runs, with which rule, the
   evaluations so far, the fast group seen, K, the buffer layers and the
   atoms on the fine clock, the census, the buffer's reach
------------------------------------------------------------------------- */

void FixPEJumpAsync::write_restart(FILE *fp)
{
  double list[NGLOBAL] = {};
  list[HEAD] = (two_step->has_started() ? HEAD_STARTED : 0) +
      (clock_assignment->dynamic_group() ? HEAD_DYNAMIC : 0) +
      (damping->kicked() ? DAMP_KICKED : 0) + (damping->allocated() ? DAMP_FIELDS : 0) +
      (damping->has_history(FINE_CLOCK) ? DAMP_FINE : 0) +
      (damping->has_history(COARSE_CLOCK) ? DAMP_COARSE : 0);
  list[FORMAT] = RESTART_FORMAT;
  list[FAMILY] = rule->family();
  list[POINTS] = rule->points();
  list[EVALS_TOTAL] = evals->total;
  list[NFINE] = clocks->steps();
  clock_assignment->save(&list[CLOCKS], &list[FAST_SEEN], &list[BUFFER_REACH]);
  two_step->save_census(&list[CENSUS]);
  if (comm->me == 0) {
    int size = sizeof(list);
    fwrite(&size, sizeof(int), 1, fp);
    fwrite(list, sizeof(double), NGLOBAL, fp);
  }
}

/* ---------------------------------------------------------------------- */

void FixPEJumpAsync::restart(char *buf)
{
  auto *list = reinterpret_cast<double *>(buf);
  if (static_cast<int>(list[FORMAT]) != RESTART_FORMAT)
    error->all(FLERR, "Fix {}: the restart file has another layout of the fix's state{}", style,
               PEJump::errorurl(14));
  const bool same_rule = (static_cast<int>(list[FAMILY]) == rule->family()) &&
      (static_cast<int>(list[POINTS]) == rule->points());
  const int head = static_cast<int>(list[HEAD]);
  two_step->set_started((head & HEAD_STARTED) != 0);
  evals->total = list[EVALS_TOTAL];
  two_step->load_census(&list[CENSUS]);
  const auto restarts = [&](const std::string &why) {
    if (two_step->has_started() && (comm->me == 0))
      utils::logmesg(lmp, "Fix {}: {}: the two-step scheme restarts from the current state\n",
                     style, why);
    two_step->set_started(false);
  };
  if (!same_rule) restarts("quadrature differs from the restart file");
  if (static_cast<int>(list[NFINE]) != clocks->steps()) restarts("K differs from the restart file");
  clock_assignment->restore(&list[CLOCKS], &list[FAST_SEEN], &list[BUFFER_REACH]);
  if (head & HEAD_DYNAMIC) clock_assignment->restored_from_dynamic();
  // (the per-atom fields may hold the second half of an impulse)
  impulse_pending = (field.end_impulse >= 0);
  damping->set_kicked((head & DAMP_KICKED) != 0);
  if (head & DAMP_FIELDS) damping->allocate();
  damping->set_history(((head & DAMP_FINE) != 0) && two_step->has_started(), FINE_CLOCK);
  damping->set_history(((head & DAMP_COARSE) != 0) && two_step->has_started(), COARSE_CLOCK);
}

/* ----------------------------------------------------------------------
   if the atoms on the fine clock changed since the last run (the fast
   group redefined, a restart with another fast group or buffer), the
   two-step state of the atoms that changed clock no longer fits: the
   scheme restarts
------------------------------------------------------------------------- */

void FixPEJumpAsync::check_clocks()
{
  if (!clock_assignment->changed() || !two_step->has_started()) return;
  if (comm->me == 0)
    utils::logmesg(lmp,
                   "Fix {}: the atoms on the fine clock changed since the last run: restarting "
                   "the two-step scheme at this coarse node\n",
                   style);
  two_step->set_started(false);
}

/* ----------------------------------------------------------------------
   the work arrays of the owned atoms that the rule needs
------------------------------------------------------------------------- */

void FixPEJumpAsync::grow_work()
{
  work->ensure(others->add_forces() ? atom->nlocal + atom->nghost : atom->nlocal, needed_work());
}

/* ---------------------------------------------------------------------- */

int FixPEJumpAsync::needed_work() const
{
  return (1 << SUM) | (others->add_forces() ? 1 << COPY : 0) |
      (shows_centre_velocities() ? 1 << VFREE : 0);
}

/* ----------------------------------------------------------------------
   other fixes add forces, whose impulse sits at the primary coarse node
   inside the coarse step: they see the velocities of CentreVelocity there
------------------------------------------------------------------------- */

bool FixPEJumpAsync::shows_centre_velocities() const
{
  return (field.half_impulse >= 0) && others->add_forces();
}

/* ----------------------------------------------------------------------
   the end of a run: remember the velocities
------------------------------------------------------------------------- */

void FixPEJumpAsync::post_run()
{
  bigint builds = 0;
  MPI_Allreduce(&builds_inside, &builds, 1, MPI_LMP_BIGINT, MPI_MAX, world);
  if (builds && (comm->me == 0))
    utils::logmesg(lmp, "Fix {}: {} neighbor list builds by the fix (inside coarse steps)\n", style,
                   builds);
  builds_inside = 0;
  two_step->end_run(group_atoms(), node_sampler->tallied(true));
  // the fine clock as the run leaves it (atoms lost through a boundary
  // leave it too), for the next run to compare
  clock_assignment->changed();
  clock_assignment->report(style);
}
