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
#include "group.h"
#include "memory.h"
#include "modify.h"
#include "neigh_list.h"
#include "neighbor.h"
#include "output.h"
#include "pair.h"
#include "pe_jump_atom_state.h"
#include "pe_jump_auto_quadrature.h"
#include "pe_jump_errors.h"
#include "pe_jump_force_sampler.h"
#include "pe_jump_node_sampler.h"
#include "pe_jump_options.h"
#include "pe_jump_other_fixes.h"
#include "pe_jump_parasitic_damping.h"
#include "pe_jump_quadrature.h"
#include "pe_jump_stability_guard.h"
#include "pe_jump_step_control.h"
#include "pe_jump_two_step.h"
#include "pe_jump_work_forces.h"
#include "timer.h"
#include "update.h"

#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <memory>

using namespace LAMMPS_NS;
using namespace FixConst;

// the global restart values, in this order: the state bits (HEAD_*), the
// layout's format, the rule, the evaluations so far, the step history
// (StepControl, 2 values), the census of the last run's end
enum RestartValue { HEAD, FORMAT, FAMILY, POINTS, EVALS_TOTAL, STEPS, CENSUS = STEPS + 2 };
static constexpr int NGLOBAL = CENSUS + PEJump::TwoStep::NCENSUS;
static constexpr int RESTART_FORMAT = 20261206;
// the scheme had started; damp auto damps since a velocity change; the
// last step was damped (the damping's per-atom values are valid); they
// follow the scheme's per-atom state
static constexpr int HEAD_STARTED = 1, HEAD_KICKED = 4, HEAD_DAMPED = 8, HEAD_DAMP_FIELDS = 16;

/* ---------------------------------------------------------------------- */

template <typename Function> void FixPEJump::for_atoms(Function &&one) const
{
  group_atoms().each(atom->mask, atom->nlocal, one);
}
using PEJump::AtomSet;
using PEJump::AtomState;
using PEJump::ForceSampler;
using PEJump::NodeSampler;
using PEJump::OtherFixes;
using PEJump::Quadrature;
using PEJump::StabilityGuard;
using PEJump::StepControl;

/* ---------------------------------------------------------------------- */

FixPEJump::FixPEJump(LAMMPS *lmp, int narg, char **arg) :
    Fix(lmp, narg, arg), rule(nullptr), auto_quadrature(nullptr), sampler(nullptr),
    node_sampler(nullptr), state(nullptr), two_step(nullptr), step_control(nullptr),
    damping(nullptr), guard(nullptr), others(nullptr), work(nullptr)
{
  opts = new PEJump::Options;
  evals = new PEJump::Evaluations;
  if (narg < 3) utils::missing_cmd_args(FLERR, "fix pe_jump", error);

  opts->parse(lmp, style, narg, arg, 3, false);

  rule = new Quadrature(static_cast<Quadrature::Family>(opts->family), opts->npoints);
  sampler = new ForceSampler(lmp);
  node_sampler = new NodeSampler(lmp, sampler);
  guard = new StabilityGuard(lmp);
  others = new OtherFixes(lmp, this);
  work = new PEJump::WorkForces(lmp, 2);

  if (opts->auto_tol > 0.0) {
    if (opts->sample_mask != ForceSampler::ALL)
      error->all(FLERR, "Fix {} quadrature auto samples all force contributions", style);
    auto_quadrature = new PEJump::AutoQuadrature(lmp, id, opts->auto_tol);
  }

  // the per-atom state; step control adds the force history it needs
  state = new AtomState(lmp);
  two_step = new PEJump::TwoStep(lmp, *state, rule->reuses_start_node());
  const bool compensate = (opts->compensate < 0) ? (opts->adapt_eps > 0.0)
                                                 : (opts->compensate != 0);
  step_control = new StepControl(lmp, *state, opts->adapt_eps, opts->adapt_dtmin, opts->adapt_dtmax,
                                 compensate);
  // adapt changes the time step, as fix dt/reset does: LAMMPS then keeps
  // the elapsed time of changing steps (update->atime), which
  // reset_timestep would lose, so it refuses that command beside the fix
  if (step_control->adapts()) time_depend = 1;
  damping = new PEJump::ParasiticDamping(*state);

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

  reinit_pending = opened_ahead = before_open = born = 0;
  h_step = 0.0;
  end_time = 0.0;
  *evals = {};

  for (int i = 0; i < atom->nlocal; i++) FixPEJump::set_arrays(i);
  two_step->fresh = born = 0;
  advance_pending = 0.0;
  atom->add_callback(Atom::GROW);
  atom->add_callback(Atom::RESTART);
}

/* ----------------------------------------------------------------------
   what the fix creates besides itself, once it exists: quadrature auto
   needs the potential energy at every step, so a compute pe asks the
   Verlet loop to tally it
------------------------------------------------------------------------- */

void FixPEJump::post_constructor()
{
  if (auto_quadrature) auto_quadrature->create_compute();
}

/* ---------------------------------------------------------------------- */

FixPEJump::~FixPEJump()
{
  if (modify->get_fix_by_id(id)) {
    atom->delete_callback(id, Atom::GROW);
    atom->delete_callback(id, Atom::RESTART);
  }
  delete evals;
  delete opts;
  delete work;
  delete[] extlist;
  delete step_control;
  delete two_step;
  delete state;
  delete others;
  delete damping;
  delete guard;
  delete node_sampler;
  delete sampler;
  delete auto_quadrature;
  delete rule;
}

/* ---------------------------------------------------------------------- */

int FixPEJump::setmask()
{
  int mask = INITIAL_INTEGRATE | POST_NEIGHBOR | PRE_REVERSE | FINAL_INTEGRATE;
  if (step_control->adapts()) mask |= END_OF_STEP;
  return mask;
}

/* ----------------------------------------------------------------------
   with neigh_modify include LAMMPS clears the forces and checks the
   distances of the atoms of the include group only: every atom that the
   fix moves must be in it
------------------------------------------------------------------------- */

void FixPEJump::refuse_atoms_outside_include_group() const
{
  if (neighbor->includegroup <= 0) return;
  const int includebit = group->bitmask[neighbor->includegroup];
  const int *mask = atom->mask;
  bigint local = 0, outside = 0;
  for (int i = 0; i < atom->nlocal; i++)
    if ((mask[i] & groupbit) && !(mask[i] & includebit)) ++local;
  MPI_Allreduce(&local, &outside, 1, MPI_LMP_BIGINT, MPI_SUM, world);
  if (outside > 0)
    error->all(FLERR,
               "Fix {} moves every atom of its group every step, but {} of them are not in the "
               "neigh_modify include group {}{}",
               style, outside, group->names[neighbor->includegroup], PEJump::errorurl(5));
}

/* ---------------------------------------------------------------------- */

void FixPEJump::init()
{
  two_step->init(style);
  guard->refuse_zero_skin(style, rule->only_end_nodes(), "quadrature " + rule->name());
  refuse_atoms_outside_include_group();
  if (step_control->adapts()) refuse_step_counters();

  others->sort(*sampler);
  sampler->refuse_accelerators(style);
  sampler->refuse_velocity_forces(style, rule->name(), rule->only_end_nodes());
  sampler->refuse_stateful_forces(style, rule->name(), rule->only_end_nodes());

  // forces that the rule does not integrate (other fixes that add forces,
  // contributions left out by sample) act as impulses at the primary node:
  // the force there is split into the sampled part and the rest. The
  // impulse must sit at the centre of the step or at its end, so a rule
  // whose primary node is elsewhere (an even Gauss-Legendre rule) then
  // gets the centre as an extra node

  const int present = sampler->present();
  const bool centre = split_primary() && rule->primary_off_centre() && !auto_quadrature;
  if (centre != (rule->size() != rule->points())) {
    auto *other = new Quadrature(rule->family(), rule->points(), centre);
    delete rule;
    rule = other;
  }
  // thermostats drive the parasitic period-2 mode, which the scheme does
  // not damp: damp it over the damp time (auto: beside thermostats only,
  // over AUTO_STEPS steps, from the start if one adds forces, else from
  // the first step where a velocity changed). Lobatto 2 is velocity
  // Verlet, whose jumps [v]^n = h a^n have no such mode: auto leaves it be
  damping->init(opts->damp_time, update->dt, (others->thermostats() > 0) && !rule->only_end_nodes(),
                others->thermostat_forces() > 0);
  maxexchange = state->values();    // (damping may have added its fields)
  check_others_for_rule();
  if (auto_quadrature) auto_quadrature->check_compute(style);
  if (present && !(opts->sample_mask & present) && (comm->me == 0))
    error->warning(FLERR, "Fix {} samples none of the force contributions present{}", style,
                   PEJump::errorurl(17));
}

/* ----------------------------------------------------------------------
   adapt changes the time step: other fixes that set it, or that count
   steps as if it were constant, are refused
------------------------------------------------------------------------- */

void FixPEJump::refuse_step_counters() const
{
  for (const auto &ifix : modify->get_fix_list()) {
    if (utils::strmatch(ifix->style, "^dt/reset"))
      error->all(FLERR, "Fix {} adapt and fix {} ({}) both set the time step: use one of them{}",
                 style, ifix->id, ifix->style, PEJump::errorurl(35));
    // (fix nve with fix dt/reset has the same problem in LAMMPS)
    if (utils::strmatch(ifix->style, "^deform"))
      error->all(FLERR,
                 "Fix {} adapt changes the time step, but fix {} ({}) changes the box by the step "
                 "count{}",
                 style, ifix->id, ifix->style, PEJump::errorurl(36));
  }
}

/* ----------------------------------------------------------------------
   other fixes and computes against the rule: where it samples the forces
   (inside the step or at its end) and how often
------------------------------------------------------------------------- */

void FixPEJump::check_others_for_rule() const
{
  const bool primary_at_end = (rule->node[rule->primary()] == 1.0);
  others->refuse_shared_atoms();
  others->refuse_for_rule(rule->name(), primary_at_end, rule->only_end_nodes());
  others->warn_step_number(rule->name(), primary_at_end, rule->only_end_nodes());
  others->warn_energy_inside_step(rule->name(), primary_at_end);
  others->warn_langevin_inside_step(rule->name(), primary_at_end);
  if (!primary_at_end)
    node_sampler->refuse_step_end_side_effects(
        style, fmt::format("with quadrature {} output steps have two evaluations", rule->name()));
}

/* ----------------------------------------------------------------------
   an energy minimization moves the atoms and keeps the velocities: the
   next run restarts the scheme
------------------------------------------------------------------------- */

void FixPEJump::min_setup(int /*vflag*/)
{
  two_step->atoms_minimized();
}

/* ----------------------------------------------------------------------
   forces at the current positions q^n are known here. Start the two-step
   scheme, or continue it if the state carried over (earlier run, restart)
------------------------------------------------------------------------- */

void FixPEJump::setup(int /*vflag*/)
{
  // where the input decides, other integrators are refused here, before
  // the first step: dynamic groups are up to date now (not yet at init),
  // and atoms inserted during the run would be seen only when they arrive
  others->refuse_shared_atoms();
  others->refuse_inserted_atoms(rule->name(), !rule->only_end_nodes());
  state->ensure(atom->nlocal);
  grow_work();
  guard->start_run(!watch(OtherFixes::BETWEEN_STEPS | OtherFixes::INSIDE_STEP) &&
                   !domain->box_change);
  opened_ahead = 0;
  evals->step = 0.0;
  // a new time step between runs: the jumps fit the old one (restart), unless
  // they are to be carried over (compensate given, or adapt)
  two_step->agree_on_started(group_atoms(), style,
                             (opts->compensate < 0) && !step_control->adapts(),
                             node_sampler->tallied(true));
  node_sampler->ask_energy_at(update->laststep);    // for the next run to compare
  const int change = two_step->has_started() ? two_step->velocity_change(group_atoms(), true) : 0;
  const double pe = step_control->adapts() ? potential_now() : 0.0;
  if ((!two_step->has_started() || (change == 2)) && !two_step->reading_snapshots())
    step_control->first_step(style, group_atoms(), atom->f, pe);
  if (!two_step->has_started())
    start_scheme(nullptr, true);
  else if (change == 2)
    start_scheme("velocities were changed since the last run: restarting the two-step scheme "
                 "from the current positions and velocities",
                 true);
  else
    refresh_start_nodes();
  if ((change == 1) && (comm->me == 0))
    utils::logmesg(lmp, "Fix {}: all velocities were reversed: continuing backwards in time\n",
                   style);
  two_step->fresh = 0;
  if (!rule->only_end_nodes()) others->refuse_interactions(rule->name().c_str());
  if (step_control->adapts())
    step_control->start_run(style, pe + two_step->energies(group_atoms())[0]);
  if (damping->automatic_on() && !two_step->reading_snapshots()) damping->note(lmp, style, false);
  if (auto_quadrature) auto_quadrature->start_run(*node_sampler, opts->sample_mask);
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
  if (two_step->awaits_setup() && two_step->check_run_without_setup(style, group_atoms(), false))
    next_reneighbor = update->ntimestep;
  begin_step();
  // the Verlet loop's forces are taken at the primary node: a force that
  // depends on time (a variable of time, e.g. in fix addforce) must see
  // the node's time, or its impulse is off by h F'/2 per step (first
  // order). Put back at the end of the step, before anything else looks.
  // Another time integrator needs the step end's time for its atoms
  end_time = update->atime;
  if (!others->integrate_others()) update->atime -= (1.0 - rule->node[rule->primary()]) * h_step;
}

/* ----------------------------------------------------------------------
   the step begins: v^n -> v^{n+1/2}, free flight to the primary node
------------------------------------------------------------------------- */

void FixPEJump::begin_step()
{
  if (reinit_pending) start_scheme(nullptr, false);
  reinit_pending = 0;

  h_step = update->dt;
  if (opened_ahead) {
    // the last step already began this one (nothing looked in between)
    check_lists();
    opened_ahead = 0;
    return;
  }
  node_impulses();
  if (open_while_moving()) {
    // the check takes v^n + [v]^n/2, then one pass begins the steps and moves
    before_open = 1;
    check_lists();
    before_open = 0;
    open_and_advance(rule->node[rule->primary()] * h_step);
    return;
  }
  open_steps();
  if (step_control->keeps_history()) {
    grow_work();
    if (step_control->compensate(h_step, group_atoms(), atom->v, two_step->jump(), fsum())) {
      two_step->forget_energies();
      guard->forget_stats();
    }
  }
  check_lists();
  advance(rule->node[rule->primary()] * h_step);
}

/* ----------------------------------------------------------------------
   impulses at the node q^n: a velocity that another fix changed since the
   last step is an impulse there (the free-flight velocity v^n + [v]^n/2
   follows it, the jump stays); damp auto takes note. With a Lobatto rule,
   forces that the rule does not integrate give the second half of their
   kick (the first half went into the node velocity at the end of the last
   step, as in velocity Verlet): see open_steps()
------------------------------------------------------------------------- */

void FixPEJump::node_impulses()
{
  if (!watch(OtherFixes::BETWEEN_STEPS)) return;
  if (!two_step->any_changed(group_atoms())) return;
  damping->impulse_here();
  // the speeds taken at the end of the last step no longer bound the
  // excursion of this step's nodes
  guard->forget_stats();
}

/* ----------------------------------------------------------------------
   the steps of all atoms of the group begin: v^{n+1/2} = v^n + [v]^n/2
   (and the second half of the end kick of forces outside a Lobatto rule)
------------------------------------------------------------------------- */

void FixPEJump::open_steps()
{
  two_step->open(group_atoms(), false);
  if (!(split_primary() && rule->has_end_nodes())) return;
  double **v = atom->v;
  double **f = atom->f;
  double **fstart = two_step->fstart();
  const double dth = 0.5 * h_step * force->ftm2v;
  for_atoms([&](int i) {
    if (std::isnan(fstart[i][0])) return;
    const double dtfm = dth * two_step->inverse_mass_of(i);
    for (int k = 0; k < 3; k++) v[i][k] += dtfm * (f[i][k] - fstart[i][k]);
  });
  guard->forget_stats();
}

/* ---------------------------------------------------------------------- */

bool FixPEJump::watch(int when) const
{
  return others->may_change_velocities(when);
}

/* ---------------------------------------------------------------------- */

PEJump::FreeFlight FixPEJump::free_flight() const
{
  return {atom->v, two_step->jump(), nullptr, before_open != 0};
}

/* ----------------------------------------------------------------------
   the steps can begin in the pass that moves the atoms if nothing acts on
   the free-flight velocities in between (compensation, the second half of
   an end kick)
------------------------------------------------------------------------- */

bool FixPEJump::open_while_moving() const
{
  return !step_control->keeps_history() && !(split_primary() && rule->has_end_nodes());
}

/* ----------------------------------------------------------------------
   open_steps() and advance() in one pass, with the same operations
------------------------------------------------------------------------- */

void FixPEJump::open_and_advance(double t)
{
  double **x = atom->x;
  double **v = atom->v;
  double **jump = two_step->jump();
  const double now = advance_now(t);
  for_atoms([&](int i) {
    for (int k = 0; k < 3; k++) {
      v[i][k] += 0.5 * jump[i][k];
      x[i][k] += now * v[i][k];
    }
  });
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
  const double now = advance_now(t);
  for_atoms([&](int i) {
    for (int k = 0; k < 3; k++) x[i][k] += now * v[i][k];
  });
}

/* ----------------------------------------------------------------------
   on a step that rebuilds the lists, they are built (and atoms exchanged
   and sorted) at the end node q^{n+1}, as with fix nve, so that a run
   continued from a restart, which builds them there, reproduces the
   unbroken run; the atoms go back to the primary node after the build
------------------------------------------------------------------------- */

double FixPEJump::advance_now(double t)
{
  const bool later = (t != h_step) && guard->rebuild_forced();
  advance_pending = later ? t - h_step : 0.0;
  return later ? h_step : t;
}

/* ----------------------------------------------------------------------
   the lists were built at the end node: back to the primary node
------------------------------------------------------------------------- */

void FixPEJump::post_neighbor()
{
  if (advance_pending == 0.0) return;
  double **x = atom->x;
  double **v = atom->v;
  for_atoms([&](int i) {
    for (int k = 0; k < 3; k++) x[i][k] += advance_pending * v[i][k];
  });
  advance_pending = 0.0;
  comm->forward_comm();
}

/* ---------------------------------------------------------------------- */

/* ---------------------------------------------------------------------- */

bool FixPEJump::split_primary() const
{
  const int present = sampler->present();
  return others->add_forces() || ((opts->sample_mask & present) != present);
}

/* ---------------------------------------------------------------------- */

bool FixPEJump::use_copy() const
{
  const int present = sampler->present();
  return others->add_forces() && ((opts->sample_mask & present) == present);
}

/* ---------------------------------------------------------------------- */

AtomSet FixPEJump::group_atoms() const
{
  return {groupbit, nullptr};
}

/* ----------------------------------------------------------------------
   forces of this step are evaluated at q^n + c h v^{n+1/2} for c from the
   first node sampled (the start node of a Lobatto rule is reused) to the
   last one, or to the end node q^{n+1} if the step tallies energy or virial
------------------------------------------------------------------------- */

void FixPEJump::check_lists()
{
  const int first = rule->first_sampled();
  const double c_hi = node_sampler->step_end_evaluated() ? 1.0 : rule->node.back();
  check_excursion(rule->node[first] * h_step, c_hi * h_step);
}

/* ----------------------------------------------------------------------
   remember which energy/virial tallies this step needs and, if the primary
   force must be split, copy the force field part before other fixes add to it
------------------------------------------------------------------------- */

void FixPEJump::pre_reverse(int eflag, int vflag)
{
  node_sampler->note_step_flags(eflag, vflag);
  if (!use_copy()) return;
  grow_work();
  const int nall = atom->nlocal + atom->nghost;
  if (nall) memcpy(&fsample()[0][0], &atom->f[0][0], 3 * sizeof(double) * nall);
}

/* ----------------------------------------------------------------------
   forces at the primary node are known: sample the other nodes, jump the
   momenta, and move on to the end node q^{n+1}
------------------------------------------------------------------------- */

void FixPEJump::final_integrate()
{
  grow_work();
  evals->step = 1.0;

  // a velocity changed by another fix during the step (wall/reflect, ...)
  // changed the free-flight velocity, which atom->v holds: an impulse

  // with a single node, evaluated by the Verlet loop with nothing else to
  // separate, the forces there are the quadrature average itself
  const bool direct = (rule->size() == 1) && !split_primary() && !step_control->adapts();
  // the nodes are sampled at their own times (from the primary node's)
  node_sampler->time_follows_nodes(!others->integrate_others());
  if (!direct) quadrature_sum();
  node_sampler->time_follows_nodes(false);
  update->atime = end_time;
  double **favg = direct ? atom->f : fsum();

  const double rest = (1.0 - rule->node[rule->primary()]) * h_step;
  if (born) {
    // (a Lobatto rule's sampled force at the end node is its next start node)
    double **fp = rule->has_end_nodes() ? two_step->fstart()
                                        : (split_primary() ? fsample() : atom->f);
    start_new_atoms(fp, rest);
    born = 0;
  }
  double mag[2] = {0.0, 0.0};
  opened_ahead = may_open_ahead();
  if (opened_ahead)
    two_step->jump_loop(group_atoms(), favg,
                        {h_step, rest, rule->node[rule->primary()] * update->dt, false}, mag);
  else
    finish_step(favg, rest, mag);
  guard->set_stats(mag[0], mag[1]);
  damping->done();

  if (rest != 0.0)
    tally_at_node();
  else
    node_sampler->ghosts_with_owned(others->step_observed());
  if (others->integrate_others() && (neighbor->ago == 0) && !rule->only_end_nodes())
    others->refuse_interactions(rule->name().c_str());
  evals->total += evals->step;
  two_step->forget_energies();
  step_control->step_done(h_step);
}

/* ----------------------------------------------------------------------
   the owned atoms of the group (those listed in only, if given) jump with
   the quadrature sums favg of their forces over the step h_step and move on
   by rest from the primary node to q^{n+1} (quadrature_sum() kept the
   start-node forces of the next step); the force history is kept.
   mag[0], mag[1]: the largest |v^{n+3/2}|^2 and |[v]^{n+1}|^2 so far, for
   the stability guard
------------------------------------------------------------------------- */

void FixPEJump::finish_step(double **favg, double rest, double *mag)
{
  double **x = atom->x;
  double **v = atom->v;
  double **f = atom->f;
  double **jump = two_step->jump();
  const bool keep_start = rule->has_end_nodes();
  double **fhist = step_control->next_history();
  const bool fingerprint = watch(OtherFixes::BETWEEN_STEPS);
  double *vsig = fingerprint ? two_step->vsig() : nullptr;
  const double kick = 2.0 * h_step * force->ftm2v;
  // forces not integrated by the rule: an impulse at the centre of the step
  // (position Verlet), or at its end node half now and half at the start of
  // the next step (velocity Verlet)
  const bool centre_kick = split_primary() && !keep_start;
  const bool end_kick = split_primary() && keep_start;
  // parasitic damping: the jump is pulled towards the smooth jump at the
  // node, centred on it from this step's and the last step's impulses
  const PEJump::ParasiticDamping::Step *damp = damping->step(h_step);
  if (!centre_kick && !end_kick && !fhist) {
    two_step->jump_loop(group_atoms(), favg, {h_step, rest, -1.0, fingerprint}, mag, damp);
    return;
  }
  double vv = mag[0], jj = mag[1];
  double **sampled = fsample();
  // per atom in registers (the arrays may alias for all the compiler knows)
  const auto one = [&](int i) {
    const double dtfm = kick * two_step->inverse_mass_of(i);
    double vh[3] = {v[i][0], v[i][1], v[i][2]};    // v^{n+1/2}
    double jmp[3] = {jump[i][0], jump[i][1], jump[i][2]};
    double vnew[3];
    for (int k = 0; k < 3; k++) {
      if (centre_kick) vh[k] += 0.5 * dtfm * (f[i][k] - sampled[i][k]);
      x[i][k] += rest * vh[k];
      if (end_kick) vh[k] += 0.25 * dtfm * (f[i][k] - sampled[i][k]);
      const double d = dtfm * favg[i][k];
      if (damp) damp->pull(i, k, dtfm, favg[i][k], d, jmp[k]);
      vnew[k] = PEJump::TwoStep::jump_component(d, vh[k], jmp[k]);
      v[i][k] = vh[k];
      jump[i][k] = jmp[k];
      if (fhist) fhist[i][k] = favg[i][k];
    }
    if (vsig) vsig[i] = PEJump::velocity_fingerprint(v[i]);
    vv = MAX(vv, vnew[0] * vnew[0] + vnew[1] * vnew[1] + vnew[2] * vnew[2]);
    jj = MAX(jj, jmp[0] * jmp[0] + jmp[1] * jmp[1] + jmp[2] * jmp[2]);
  };
  for_atoms(one);
  mag[0] = vv;
  mag[1] = jj;
}

/* ----------------------------------------------------------------------
   true if the next step can begin as this one ends (the jump loop moves
   the atoms on to its primary node): a single-node rule or a Lobatto rule
   (the primary node is the step end: the other nodes are sampled from
   there), without split or step-size history, nothing that looks at the
   atoms or may change their velocities in between, lists checked by
   distance, and no timeout that may end the run before the next step
------------------------------------------------------------------------- */

bool FixPEJump::may_open_ahead() const
{
  return ((rule->size() == 1) || rule->has_end_nodes()) && !split_primary() &&
      !step_control->keeps_history() && !damping->active() && neighbor->dist_check &&
      !reinit_pending && !watch(OtherFixes::BETWEEN_STEPS) && !others->step_observed() &&
      !timer->has_timeout();
}

/* ----------------------------------------------------------------------
   the atoms are at the node q^{n+1} but the last force evaluation was
   elsewhere: on steps that tally energy or virial evaluate everything
   once more at the node (the forces there replace those of the primary
   node, which the next step does not use); on output steps bring the
   ghosts to the node
------------------------------------------------------------------------- */

void FixPEJump::tally_at_node()
{
  evals->step +=
      node_sampler->at_step_end(others->step_observed(), others->integrate_others() ? groupbit : 0);
}

/* ----------------------------------------------------------------------
   the end of a run: remember the velocities; quadrature auto says how
   often each rule was taken
------------------------------------------------------------------------- */

void FixPEJump::post_run()
{
  // the velocities as the run leaves them, for the next run to compare
  two_step->end_run(group_atoms(), node_sampler->tallied(true));

  if (auto_quadrature) auto_quadrature->report(style);
}

/* ---------------------------------------------------------------------- */

void FixPEJump::end_of_step()
{
  if (step_control->adapts()) step_control->choose_next(group_atoms(), fsum(), two_step->jump());
}

/* ----------------------------------------------------------------------
   (re)start the two-step scheme from the current positions q^0, velocities
   v^0 and forces F(q^0):
     kick:  v^{1/2} = v^0 + (h/2) F/m, [v]^0 = h F/m
     paper: v^{1/2} = v^0,            [v]^0 = 0
   the node velocity v^0 stays in atom->v (its fingerprint tells a later
   run whether velocities were changed in between).
   with_start: also store the sampled force at q^0 as the Lobatto start node
   (not when only the kick is redone with the complete forces)
------------------------------------------------------------------------- */

void FixPEJump::start_scheme(const char *why, bool with_start)
{
  if (why && (comm->me == 0)) utils::logmesg(lmp, "Fix {}: {}\n", style, why);

  grow_work();
  if (with_start && rule->reuses_start_node())
    store_start_node();
  else if (with_start && split_primary())
    primary_sampled_force();

  // the jump takes the forces that the rule integrates
  const double kick = (opts->init_style == PEJump::Options::KICK) ? 1.0 : 0.0;
  two_step->start(group_atoms(), split_primary() ? fsample() : atom->f, kick, [&](int) {
    return update->dt;
  });

  // fixes defined after this one act on the forces after its setup(): redo
  // the initial kick with the complete forces at the first step

  reinit_pending = with_start && (opts->init_style == PEJump::Options::KICK) && !split_primary() &&
      sampler->has_projections();
  two_step->set_started(true);
  step_control->forget();
  damping->forget_history();
  guard->forget_stats();
}

/* ----------------------------------------------------------------------
   Lobatto rules: the sampled force at q^0 is the start node of the first step
------------------------------------------------------------------------- */

void FixPEJump::store_start_node()
{
  primary_sampled_force();
  double **fstart = two_step->fstart();
  for_atoms([&](int i) {
    for (int k = 0; k < 3; k++) fstart[i][k] = fsample()[i][k];
  });
}

/* ----------------------------------------------------------------------
   sampled force-field force at the primary node into fsample() (owned atoms)
------------------------------------------------------------------------- */

void FixPEJump::primary_sampled_force()
{
  const int nlocal = atom->nlocal;
  const size_t nbytes = 3 * sizeof(double) * nlocal;
  if (!nlocal && !split_primary()) return;

  if (!split_primary()) {
    memcpy(&fsample()[0][0], &atom->f[0][0], nbytes);
  } else if (use_copy()) {
    if (force->newton) comm->reverse_comm(this);
  } else {
    NodeSampler::Keep keep(*node_sampler);
    sampler->compute(opts->sample_mask, 0, 0);
    if (nlocal) memcpy(&fsample()[0][0], &atom->f[0][0], nbytes);
    evals->step += sampler->fraction(opts->sample_mask);
  }
  // at setup, fixes after this one have not yet acted on the forces
  if (sampler->has_projections() && (split_primary() || update->setupflag)) project_sampled();
}

/* ----------------------------------------------------------------------
   the force-replacing fixes act on the sampled force at the primary node
   as they did on the total force there
------------------------------------------------------------------------- */

void FixPEJump::project_sampled()
{
  NodeSampler::Keep keep(*node_sampler);
  const size_t nbytes = 3 * sizeof(double) * atom->nlocal;
  if (nbytes) memcpy(&atom->f[0][0], &fsample()[0][0], nbytes);
  sampler->project();
  if (nbytes) memcpy(&fsample()[0][0], &atom->f[0][0], nbytes);
}

/* ----------------------------------------------------------------------
   atoms created since the last step (fix deposit, create_atoms) have no
   start-node force: at setup all start nodes are taken again at q^n, and
   during a run a new atom's start node is its first primary node
------------------------------------------------------------------------- */

void FixPEJump::refresh_start_nodes()
{
  int any = 0;
  MPI_Allreduce(&two_step->fresh, &any, 1, MPI_INT, MPI_MAX, world);
  if (!any || !rule->reuses_start_node()) return;

  // the new atoms (start node still unknown) also get the initial kick
  AtomList fresh;
  double **fstart = two_step->fstart();
  for_atoms([&](int i) {
    if (std::isnan(fstart[i][0])) fresh.push_back(i);
  });
  store_start_node();
  if (opts->init_style != PEJump::Options::KICK) return;
  double **jump = two_step->jump();
  for (const int i : fresh) {
    const double dtfm = force->ftm2v * update->dt * two_step->inverse_mass_of(i);
    for (int k = 0; k < 3; k++) jump[i][k] = dtfm * fstart[i][k];
  }
}

/* ----------------------------------------------------------------------
   fsum() = sum_k w_k F_sampled(q_k) + (F(q_p) - F_sampled(q_p)) over the nodes
   q_k = q^n + c_k h v^{n+1/2}; the primary node p was evaluated by the Verlet
   loop, a Lobatto start node is the previous step's end node
------------------------------------------------------------------------- */

void FixPEJump::quadrature_sum()
{
  if (auto_quadrature) {
    auto_quadrature_sum();
    return;
  }

  const int p = rule->primary();
  const int reuse_start = rule->reuses_start_node();
  double **fstart = two_step->fstart();

  if (split_primary()) primary_sampled_force();

  // a Lobatto rule's primary node is the end node: its sampled forces are
  // the start node of the next step, kept in fstart once the sum has read
  // this step's start node
  double **fp = split_primary() ? fsample() : atom->f;
  double **sum = fsum();
  const auto begin = rule->start_sum();
  for_atoms([&](int i) {
    begin(fp[i], reuse_start ? fstart[i] : nullptr, sum[i]);
  });

  const int first = rule->first_sampled();
  if (rule->size() - first <= 1) return;
  // with a Lobatto rule the total force at the primary node (the step end)
  // is needed afterwards only for the impulses of forces outside the rule,
  // or if something looks at it: it is then fstart again, which holds this
  // fix's atoms only, so that beside other atoms (of another integrator,
  // frozen ones) the forces are kept instead
  const bool observed = atom->nlocal && (others->step_observed() || node_sampler->tally_step());
  const bool keep_forces = split_primary() || !reuse_start ||
      (observed && !group_holds_all_local());
  const int evaluated =
      node_sampler->sum_nodes(*rule, first, p, h_step, -rule->node[p] * h_step, free_flight(),
                              group_atoms(), opts->sample_mask, fsum(), nullptr, keep_forces);
  evals->step += evaluated * sampler->fraction(opts->sample_mask);
  if (!keep_forces && observed)
    memcpy(&atom->f[0][0], &fstart[0][0], 3 * sizeof(double) * atom->nlocal);
}

/* ---------------------------------------------------------------------- */

bool FixPEJump::group_holds_all_local() const
{
  if (igroup == 0) return true;    // LAMMPS' group all
  const int *mask = atom->mask;
  for (int i = 0; i < atom->nlocal; i++)
    if (!(mask[i] & groupbit)) return false;
  return true;
}

/* ----------------------------------------------------------------------
   quadrature auto (see PEJump::AutoQuadrature): the start node is the
   previous end node (taken at the first evaluation of a new atom), the end
   node the Verlet evaluation
------------------------------------------------------------------------- */

void FixPEJump::auto_quadrature_sum()
{
  double **fstart = two_step->fstart();
  primary_sampled_force();    // F(q^{n+1}) into fsample()
  for_atoms([&](int i) {
    if (std::isnan(fstart[i][0]))
      for (int k = 0; k < 3; k++) fstart[i][k] = fsample()[i][k];
  });
  const int evaluated = auto_quadrature->sum(*node_sampler, opts->sample_mask, group_atoms(),
                                             free_flight(), h_step, fstart, fsample(), fsum());
  evals->step += evaluated * sampler->fraction(opts->sample_mask);
  // the end node is the start node of the next step
  for_atoms([&](int i) {
    for (int k = 0; k < 3; k++) fstart[i][k] = fsample()[i][k];
  });
}

/* ----------------------------------------------------------------------
   before moving: the nodes of this step lie on x + t v^{n+1/2}, t in
   [lo, hi]; the stability guard measures them (the magnitudes were taken
   by final_integrate() unless a velocity changed since), and none if the
   Verlet loop's own check covers the only node
------------------------------------------------------------------------- */

void FixPEJump::check_excursion(double lo, double hi)
{
  const double cp = rule->node[rule->primary()] * h_step;
  const bool primary_only = (lo == cp) && (hi == cp);
  const bool ends_checked = guard->ends_checked(*rule, lo, hi, h_step);
  double **xhold = (neighbor->dist_check && !primary_only && !ends_checked) ? neighbor->get_xhold()
                                                                            : nullptr;
  if (opened_ahead) {
    // the atoms are at the primary node already: measure the nodes from there
    lo -= cp;
    hi -= cp;
  }

  double local[StabilityGuard::NMEASURES] = {0.0, 0.0, 0.0, 0.0, 0.0};
  guard->step(h_step);
  guard->step_measures(group_atoms(), free_flight(), two_step->jump(), xhold, {h_step, lo, hi},
                       local);
  // (with them, whether another fix changed a velocity: damp auto damps
  // the parasitic mode from then on)
  if (guard->conclude(
          style, local, *damping,
          [&]() {
            return two_step->energies(group_atoms());
          },
          [&]() {
            return instability_advice();
          }))
    next_reneighbor = update->ntimestep;
}

/* ---------------------------------------------------------------------- */

std::string FixPEJump::instability_advice() const
{
  tell_largest_jump();
  // a velocity reversed by another fix (a reflecting wall, fix oneway) is
  // taken as an impulse beside the jump; the rules with interior nodes can
  // grow on many of them, lobatto 2 takes them as velocity Verlet does
  const std::string reversing = rule->only_end_nodes() ? std::string() : others->reversing_fixes();
  return fmt::format(
      "The time step {} is beyond the stability limit of the fastest motion: {}{}{}", h_step,
      step_control->adapts() ? "lower the adapt dtmin or eps"
                             : "reduce it, or use the adapt keyword",
      reversing.empty() ? ""
                        : fmt::format(". Velocities reversed by {} can also make the scheme "
                                      "grow with this rule: use quadrature lobatto 2",
                                      reversing),
      PEJump::errorurl(1));
}

/* ----------------------------------------------------------------------
   the run stops as unstable: the log names the atom with the largest jump
   (one atom's jump or the fastest motion of the whole system)
------------------------------------------------------------------------- */

void FixPEJump::tell_largest_jump() const
{
  double **jump = two_step->jump();
  struct {
    double value;
    int rank;
  } mine{-1.0, comm->me}, most{};
  int imax = -1;
  for_atoms([&](int i) {
    const double j2 = jump[i][0] * jump[i][0] + jump[i][1] * jump[i][1] + jump[i][2] * jump[i][2];
    if (j2 > mine.value) {
      mine.value = j2;
      imax = i;
    }
  });
  MPI_Allreduce(&mine, &most, 1, MPI_DOUBLE_INT, MPI_MAXLOC, world);
  if (most.value < 0.0) return;
  double info[6] = {0.0, 0.0, 0.0, 0.0, 0.0, 0.0};
  if (comm->me == most.rank) {
    const double *v = atom->v[imax];
    info[0] = static_cast<double>(atom->tag[imax]);
    for (int k = 0; k < 3; k++) info[1 + k] = atom->x[imax][k];
    info[4] = sqrt(most.value);
    info[5] = sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
  }
  MPI_Bcast(info, 6, MPI_DOUBLE, most.rank, world);
  if (comm->me == 0)
    utils::logmesg(lmp,
                   "Fix {}: the largest jump at step {}: atom {} at ({:.8g} {:.8g} {:.8g}), "
                   "|[v]| = {:.6g}, free-flight speed {:.6g}\n",
                   style, update->ntimestep, static_cast<tagint>(info[0]), info[1], info[2],
                   info[3], info[4], info[5]);
}

/* ----------------------------------------------------------------------
   potential energy at the current positions (one evaluation)
------------------------------------------------------------------------- */

double FixPEJump::potential_now()
{
  double pe = node_sampler->potential(ForceSampler::ALL);
  if (force->pair && force->pair->tail_flag) {
    const double volume = domain->xprd * domain->yprd * domain->zprd;
    pe += force->pair->etail / volume;
  }
  return pe;
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
      return two_step->energies(group_atoms())[n];
    case 2:
      return update->dt;
    case 3:
      return evals->step;
    case 4:
      return evals->total;
  }
  return 0.0;
}

/* ---------------------------------------------------------------------- */

double **FixPEJump::fsum() const
{
  return work->get(SUM);
}

/* ---------------------------------------------------------------------- */

double **FixPEJump::fsample() const
{
  return work->get(SAMPLE);
}

/* ----------------------------------------------------------------------
   work arrays for the owned atoms (fsample() also for the ghosts if it is
   split off before the reverse communication), only those the rule needs
------------------------------------------------------------------------- */

void FixPEJump::grow_work()
{
  const int need = use_copy() ? atom->nlocal + atom->nghost : atom->nlocal;
  const bool sum = (rule->size() > 1) || split_primary() || step_control->keeps_history() ||
      auto_quadrature;
  const bool sample = split_primary() || rule->has_end_nodes() || auto_quadrature;
  work->ensure(need, (sum ? 1 << SUM : 0) | (sample ? 1 << SAMPLE : 0));
}

/* ----------------------------------------------------------------------
   per-atom state: the table owns it and grows with the owned atoms
------------------------------------------------------------------------- */

void FixPEJump::grow_arrays(int /*nmax*/)
{
  state->ensure(atom->nlocal);
}

/* ---------------------------------------------------------------------- */

void FixPEJump::copy_arrays(int i, int j, int /*delflag*/)
{
  state->copy(i, j);
}

/* ----------------------------------------------------------------------
   an atom created during the simulation (fix deposit, create_atoms) has no
   jump yet (NaN until start_new_atoms() gives it one); its start-node force
   is taken at its first force evaluation (NaN until then)
------------------------------------------------------------------------- */

void FixPEJump::set_arrays(int i)
{
  state->reset(i);
  two_step->mark(i);
  for (int k = 0; k < 3; k++) two_step->jump()[i][k] = std::numeric_limits<double>::quiet_NaN();
  two_step->fresh = 1;
  born = 1;
}

/* ----------------------------------------------------------------------
   atoms created inside this step (fix deposit inserts them after
   initial_integrate, at the step end, their velocity taken as the half-step
   velocity, as fix nve does) start as the scheme starts with init kick:
   their jump is h F/m with the force fp the rule takes at the primary node,
   so that the jump relation gives them fix nve's half kick, and they stay
   at their insertion point while the others move on by rest
------------------------------------------------------------------------- */

void FixPEJump::start_new_atoms(double **fp, double rest)
{
  double **x = atom->x;
  double **v = atom->v;
  double **jump = two_step->jump();
  const double kick = h_step * force->ftm2v;
  for_atoms([&](int i) {
    if (!std::isnan(jump[i][0])) return;
    const double dtfm = kick * two_step->inverse_mass_of(i);
    for (int k = 0; k < 3; k++) {
      jump[i][k] = dtfm * fp[i][k];
      x[i][k] -= rest * v[i][k];
    }
  });
}

/* ---------------------------------------------------------------------- */

int FixPEJump::pack_exchange(int i, double *buf)
{
  return state->pack(i, buf);
}

/* ---------------------------------------------------------------------- */

int FixPEJump::unpack_exchange(int nlocal, double *buf)
{
  const int n = state->unpack(nlocal, buf);
  // (an atom created in this step may move to another rank before its start)
  if (std::isnan(two_step->jump()[nlocal][0])) born = 1;
  return n;
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
  list[HEAD] = (two_step->has_started() ? HEAD_STARTED : 0) +
      (damping->kicked() ? HEAD_KICKED : 0) + (damping->has_history() ? HEAD_DAMPED : 0) +
      (damping->allocated() ? HEAD_DAMP_FIELDS : 0);
  list[FORMAT] = RESTART_FORMAT;
  list[FAMILY] = rule->family();
  list[POINTS] = rule->points();
  list[EVALS_TOTAL] = evals->total;
  step_control->save(&list[STEPS]);
  two_step->save_census(&list[CENSUS]);
}

/* ---------------------------------------------------------------------- */

void FixPEJump::restart(char *buf)
{
  auto *list = reinterpret_cast<double *>(buf);
  if (static_cast<int>(list[FORMAT]) != RESTART_FORMAT)
    error->all(FLERR, "Fix {}: the restart file has another layout of the fix's state{}", style,
               PEJump::errorurl(14));
  const bool same_rule = (static_cast<int>(list[FAMILY]) == rule->family()) &&
      (static_cast<int>(list[POINTS]) == rule->points());
  const int head = static_cast<int>(list[HEAD]);
  two_step->set_started(((head & HEAD_STARTED) != 0) && same_rule);
  evals->total = list[EVALS_TOTAL];
  step_control->load(&list[STEPS]);
  two_step->load_census(&list[CENSUS]);
  damping->set_kicked((head & HEAD_KICKED) != 0);
  if (head & HEAD_DAMP_FIELDS) damping->allocate();
  damping->set_history(((head & HEAD_DAMPED) != 0) && two_step->has_started());
  if (!same_rule && (comm->me == 0))
    utils::logmesg(lmp,
                   "Fix {}: quadrature differs from the restart file: the two-step scheme "
                   "restarts from the current state\n",
                   style);
}

/* ---------------------------------------------------------------------- */

int FixPEJump::pack_restart(int i, double *buf)
{
  // written during a run: the velocities are the fix's own
  if (update->whichflag) two_step->mark(i);
  return state->pack_restart(i, buf);
}

/* ---------------------------------------------------------------------- */

void FixPEJump::unpack_restart(int nlocal, int nth)
{
  // a misfit is told by TwoStep::agree_on_started()
  if (!state->unpack_restart(nlocal, nth)) two_step->restart_data_unfit();
}

/* ---------------------------------------------------------------------- */

int FixPEJump::size_restart(int /*nlocal*/)
{
  return state->restart_size();
}

/* ---------------------------------------------------------------------- */

int FixPEJump::maxsize_restart()
{
  return state->restart_size();
}

/* ----------------------------------------------------------------------
   reverse communication of the force field part copied before the Verlet
   loop's own reverse communication
------------------------------------------------------------------------- */

int FixPEJump::pack_reverse_comm(int n, int first, double *buf)
{
  int m = 0;
  for (int i = first; i < first + n; i++) {
    buf[m++] = fsample()[i][0];
    buf[m++] = fsample()[i][1];
    buf[m++] = fsample()[i][2];
  }
  return m;
}

/* ---------------------------------------------------------------------- */

void FixPEJump::unpack_reverse_comm(int n, int *list, double *buf)
{
  int m = 0;
  for (int i = 0; i < n; i++) {
    const int j = list[i];
    fsample()[j][0] += buf[m++];
    fsample()[j][1] += buf[m++];
    fsample()[j][2] += buf[m++];
  }
}

/* ---------------------------------------------------------------------- */

double FixPEJump::memory_usage()
{
  return state->memory_usage() + node_sampler->memory_usage() +
      (auto_quadrature ? auto_quadrature->memory_usage() : 0.0) + work->memory_usage();
}
