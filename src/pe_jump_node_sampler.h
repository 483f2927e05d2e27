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

#ifndef LMP_PE_JUMP_NODE_SAMPLER_H
#define LMP_PE_JUMP_NODE_SAMPLER_H

#include "pe_jump_atom_set.h"
#include "pe_jump_force_sampler.h"
#include "pointers.h"

#include <string>
#include <vector>

namespace LAMMPS_NS {
namespace PEJump {
  class ForceSampler;
  class Quadrature;

  // Forces at the quadrature nodes of a step. While nodes are sampled, the
  // forces of the MD step (and the positions of the atoms that move to the
  // nodes) are kept aside by a Keep object and put back when it goes out of
  // scope. Nodes lie at q = x + t v, x the kept positions.

  class NodeSampler : protected Pointers {
   public:
    NodeSampler(class LAMMPS *, ForceSampler *);
    ~NodeSampler() override;

    // the positions kept: none, all owned atoms, those listed; or those
    // that the first evaluate_at() moves, in the same pass (SET_ON_MOVE:
    // for a Keep whose atoms are those of every evaluate_at())
    enum Positions { FORCES_ONLY, ALL_OWNED, LISTED, SET_ON_MOVE };
    class Keep {
     public:
      // forces: false if the caller does not need the forces afterwards;
      // nonzero: if given, the owned atoms but those listed have zero
      // forces, so that only theirs are kept and zeros put back for the
      // others
      Keep(NodeSampler &, Positions = FORCES_ONLY, const AtomList * = nullptr, bool forces = true,
           const AtomList *nonzero = nullptr);
      ~Keep();
      Keep(const Keep &) = delete;
      Keep &operator=(const Keep &) = delete;

      // the kept forces go back now (and not again as the Keep ends)
      void forces_back();
      // the kept positions (valid while the Keep lives); after
      // positions_taken() the Keep leaves the positions as they are: the
      // caller has set each kept atom's position itself, from these
      double **positions() const { return nodes.xkept; }
      void positions_taken() { which = FORCES_ONLY; }

     private:
      NodeSampler &nodes;
      Positions which;
      const AtomList *list;
      bool forces;
      const ForceSampler::Touched *touched;    // the sampler touches these only
      const AtomList *nonzero;                 // the others' forces are zero
      void copy_forces(double **from, double **to) const;
    };

    // move the atoms of set to x + shift v and compute the contributions in
    // mask there (forces only); needs a Keep with their positions. If the
    // time follows the nodes, the simulation time is the kept positions'
    // time + shift meanwhile (a force field that changes with time, e.g.
    // under fix adapt, sees each node's time)
    void evaluate_at(double shift, const FreeFlight &v, const AtomSet &set, int mask);
    void time_follows_nodes(bool on) { shift_time = on; }

    // acc += sum_k w_k F(q_k) over the nodes k = first .. last of rule but
    // skip, q_k = x + (scale c_k + offset) v for the atoms of set (the others
    // stay); fend (if given) gets the forces at the last node. Positions
    // are put back, and forces unless keep_forces is false (then the last
    // node's are left). Returns the number of nodes evaluated.
    int sum_nodes(const Quadrature &rule, int first, int skip, double scale, double offset,
                  const FreeFlight &v, const AtomSet &set, int mask, double **acc, double **fend,
                  bool keep_forces = true);
    // the same inside the caller's Keep, made with the positions
    // positions_for(set); with onto_acc false the first node's terms
    // replace the values in acc instead of adding to them
    int sum_nodes_in(Keep &, const Quadrature &rule, int first, int skip, double scale,
                     double offset, const FreeFlight &v, const AtomSet &set, int mask, double **acc,
                     double **fend, bool onto_acc);
    // acc = sum_k w_k F(q_k) over the nodes k = first .. last of rule in
    // order, the atoms of set moving on from node to node by free flight
    // from where they are, scale c = from: q_k = x + (scale c_k - from) v
    // (the others stay). Nothing is kept or put back: the atoms stay at
    // the last node, with its forces. Returns the number of nodes evaluated.
    int walk_nodes(const Quadrature &rule, int first, int last, double scale, double from,
                   const FreeFlight &v, const AtomSet &set, int mask, double **acc);
    // the positions a Keep keeps for sum_nodes() over set: those that the
    // first node moves, or all owned atoms for a group other than all
    // without a list
    static Positions positions_for(const AtomSet &set)
    {
      return (!set.list && (set.groupbit != 1)) ? ALL_OWNED : SET_ON_MOVE;
    }

    // the energy and virial flags the MD step's force evaluation got
    // (pre_reverse()); whether it tallies
    void note_step_flags(int eflag, int vflag)
    {
      eflag_step = eflag;
      vflag_step = vflag;
    }
    bool step_tallies() const { return eflag_step || vflag_step; }

    // the atoms are at the step end, the forces were taken elsewhere: on
    // steps that tally energy or virial, or where a dump may write the
    // forces, evaluate everything there (the forces there replace the
    // others; returns 1 evaluation), else bring the ghosts there if
    // observed (returns 0). The owned atoms outside
    // the group of groupbit (0: none) keep the forces of the MD step,
    // which another time integrator of theirs applies after this fix
    // (tallied: the energy at the step end was tallied from the evaluations
    // there, SplitTally: no evaluation, the ghosts are brought there)
    double at_step_end(bool observed, int groupbit, bool tallied = false);
    bool tally_step() const;    // the step about to begin tallies energy or virial
    // ... the global energy only (no per-atom tallies, no virial), and no
    // dump may write forces
    bool energy_only_step() const;
    // the step about to begin ends with an evaluation of everything
    // (at_step_end(): energy or virial tallied, or forces dumped)
    bool step_end_evaluated(bool tallied = false) const
    {
      return !tallied && (tally_step() || forces_dumped());
    }
    // the step ends at the primary node, evaluated by the MD step: if nodes
    // were evaluated since, the ghosts are still at the last of them; on
    // observed steps bring them to where the owned atoms are
    void ghosts_with_owned(bool observed);
    // an error if an evaluation at the step end besides the one inside
    // the step would change more than the forces: computes that add up the
    // pair tallies of all evaluations of a step (the TALLY package), bonds
    // that break inside the evaluation; why: when the fix evaluates there
    void refuse_step_end_side_effects(const char *style, const std::string &why) const;

    // potential energy of the contributions in mask at the current
    // positions (one evaluation; the forces are kept)
    double potential(int mask);

    // the potential energy of the whole force field as the last evaluation
    // of this time step tallied it (known: that evaluation tallied energy
    // and was at the current positions, at_positions), and the sum of the
    // absolute values of its parts (collective call)
    struct Tallied {
      bool known;
      double energy, magnitude;
    };
    Tallied tallied(bool at_positions) const;
    // asks LAMMPS to tally the energy in the MD step of step (thermo's pe)
    void ask_energy_at(bigint step) const;

    ForceSampler *forces() const { return sampler; }
    double memory_usage() const;

   private:
    ForceSampler *sampler;
    double **xkept, **fkept;
    int nkept;    // room for this many owned atoms
    bool keeping;
    bool keep_on_move;    // the next evaluate_at() keeps the positions it moves
    bool shift_time;
    bool ghosts_away;    // evaluate_at() moved the ghosts since the step end's communication
    int eflag_step, vflag_step;
    void make_room();
    bool forces_dumped() const;
    // acc += w f (acc = w f if replace) for the atoms of set; fend (if
    // given) = f
    void add_node(double w, const AtomSet &set, double **acc, bool replace, double **fend) const;
  };

}    // namespace PEJump
}    // namespace LAMMPS_NS

#endif
