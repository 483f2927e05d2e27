/* -*- c++ -*- ----------------------------------------------------------
   LAMMPS - Large-scale Atomic/Molecular Massively Parallel Simulator
   https://www.lammps.org/, Sandia National Laboratories
   LAMMPS development team: developers@lammps.org

   Copyright (2003) Sandia Corporation.  Under the terms of Contract
   DE-AC04-94AL85000 with Sandia Corporation, the U.S. Government retains
   certain rights in this software.  This software is distributed under
   the GNU General Public License.

   See the README file in the top-level LAMMPS directory.
------------------------------------------------------------------------- */

#ifndef LMP_PE_JUMP_OTHER_FIXES_H
#define LMP_PE_JUMP_OTHER_FIXES_H

#include "fix.h"

#include <functional>
#include <set>
#include <string>
#include <vector>

namespace LAMMPS_NS {
namespace PEJump {
  class ForceSampler;

  // What the other fixes of a run do to the atoms of this fix: replace or
  // project forces (at every quadrature node, through the ForceSampler),
  // add forces (impulses), integrate other atoms, change velocities, or
  // look at the atoms at the end of a step. Constraints are refused.

  class OtherFixes : protected Pointers {
   public:
    OtherFixes(class LAMMPS *, Fix *self);

    // hooks of other fixes where they may change velocities: between two
    // steps of this fix, or inside a step
    static constexpr int BETWEEN_STEPS =
        FixConst::INITIAL_INTEGRATE | FixConst::FINAL_INTEGRATE | FixConst::END_OF_STEP;
    static constexpr int INSIDE_STEP = FixConst::POST_INTEGRATE | FixConst::PRE_EXCHANGE |
        FixConst::PRE_NEIGHBOR | FixConst::POST_NEIGHBOR | FixConst::PRE_FORCE |
        FixConst::PRE_REVERSE | FixConst::POST_FORCE;

    void sort(ForceSampler &);    // at init
    bool add_forces() const { return nadders > 0; }
    // thermostats in the run (fixes that report the energy they exchange
    // with a reservoir, and the two-temperature models), and how many of
    // them add forces (random ones: fix langevin, fix ttm)
    int thermostats() const { return nthermostats; }
    int thermostat_forces() const { return nforcing; }
    bool may_change_velocities(int when) const { return (hooks & when) != 0; }
    bool integrate_others() const { return others_bits != 0; }

    // true if anything looks at the atoms after this step: output, the end
    // of the run, or a fix acting at the end of this step
    bool step_observed() const;

    // refuse interactions between this fix's atoms and those of another
    // time integrator (collective)
    void refuse_interactions(const char *rule_name) const;

    // fixes that rely on where fix nve leaves the atoms inside a step,
    // checked at init against the rule: fix langevin with tally yes and
    // fixes acting in initial_integrate after this fix (they take this
    // fix's atoms at the step end: the primary node must be there), and
    // time integrators that change the box (barostats, which rescale all
    // positions inside the step: only the step ends may be nodes)
    void refuse_for_rule(const std::string &rule_name, bool primary_at_end,
                         bool only_end_nodes) const;

    // the fixes that reverse velocities (wall/reflect, oneway) for messages
    std::string reversing_fixes() const;

    // (the two warnings below are given once per fix: a run that starts
    // with the same settings does not repeat them)

    // a warning if fixes whose forces may follow variables of the step
    // number (fix adapt, addforce, indent, ...) sample them where the step
    // number is not the node's: at interior nodes (fixes acting at every
    // node), or inside the step (fixes adding an impulse at the primary
    // node). Variables of time follow the nodes.
    void warn_step_number(const std::string &rule_name, bool primary_at_end, bool only_end_nodes);
    // a warning if fix langevin acts inside the step (its temperature is
    // then high by gamma h/2)
    void warn_langevin_inside_step(const std::string &rule_name, bool primary_at_end);

    // a warning if fixes that add forces add their energy to pe (fix_modify
    // energy yes) and the rule takes their forces inside the step
    void warn_energy_inside_step(const std::string &rule_name, bool primary_at_end);

    // an error if atoms of this fix are integrated by another fix too
    // (collective; at init, and at setup, where LAMMPS has brought the
    // dynamic groups up to date)
    void refuse_shared_atoms() const;

    // atoms that other fixes insert during the run (fix deposit, ...):
    // refused at setup if another time integrator will integrate them too,
    // or, with a rule that evaluates forces inside the step (interior),
    // if they will interact with atoms of another time integrator, which
    // refuse_interactions() would see only when the first of them arrive
    // (collective)
    void refuse_inserted_atoms(const std::string &rule_name, bool interior) const;

    static bool steps_own_clock(const class Fix *);
    // the group bits of the atoms that a fix inserts during a run (0 if it
    // inserts none)
    static int inserted_bits(const Fix *);
    static bool replaces_forces(const Fix *);
    static bool reads_only(const Fix *);
    static bool reverses_velocities(const Fix *);    // reflecting walls, fix oneway
    // the fixes for which keep(fix) holds, for messages: "fix 2 (wall/reflect),
    // fix 3 (oneway)" (empty if none)
    std::string named(const std::function<bool(Fix *)> &keep) const;

   private:
    Fix *self;
    // the refusals of rules whose force evaluation of the MD step lies
    // inside the step
    void refuse_inside_step(Fix *, const std::string &rule_name) const;
    // true if neigh_modify exclude may leave pairs of atoms inserted with
    // the group bits a out of the pair lists
    bool may_be_excluded(int a) const;
    int nadders;         // fixes that add forces
    int nthermostats;    // fixes that thermostat (see thermostats())
    int nforcing;        // those of them that add forces
    int others_bits;     // group bits of the other time integrators
    int hooks;           // hooks of other fixes that may change velocities
    std::vector<int> end_of_step_every;
    std::set<std::string> warned;    // the warnings given (rank 0)
    // the warning text, unless it was given before
    void warn_once(const std::string &text);
  };

}    // namespace PEJump
}    // namespace LAMMPS_NS

#endif
