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

#ifndef LMP_PE_JUMP_FORCE_SAMPLER_H
#define LMP_PE_JUMP_FORCE_SAMPLER_H

#include "pointers.h"

#include <string>
#include <vector>

namespace LAMMPS_NS {
class Fix;

namespace PEJump {
  class MovingGhosts;

  // Evaluates selected force-field contributions at the current positions of
  // the owned atoms (ghosts are brought up to date first) with the sequence
  // of the Verlet loop: forward communication, force clear, the pre_force
  // stage of other fixes, the contributions, reverse communication, with
  // the same timer stamps; then the fixes that replace or project forces act
  // on the result. Counts interactions so that evaluations can be reported
  // in units of full force evaluations.

  // force evaluations in units of one evaluation of the whole force field:
  // those of the current step (the fixes' output vector element 4) and of
  // all steps so far (element 5, kept in restart files)
  struct Evaluations {
    double step = 0.0, total = 0.0;
  };

  class ForceSampler : protected Pointers {
   public:
    enum Contribution {
      PAIR = 1 << 0,
      BOND = 1 << 1,
      ANGLE = 1 << 2,
      DIHEDRAL = 1 << 3,
      IMPROPER = 1 << 4,
      KSPACE = 1 << 5,
      ALL = (1 << 6) - 1
    };

    ForceSampler(class LAMMPS *);

    // contributions that the current force field has (call in init())
    int present() const;

    // a force field whose forces depend on the velocities (the styles that
    // need comm_modify vel yes: dpd, granular, bpm damping, ...) drives the
    // parasitic mode of the jumps unless the rule has only end nodes
    // (velocity Verlet for such forces): refused with the rule's name then
    void refuse_velocity_forces(const char *style, const std::string &rule, bool end_nodes) const;
    // an error for force styles with per-bond state that every evaluation
    // advances (peridynamics) unless the rule evaluates only at step ends
    void refuse_stateful_forces(const char *style, const std::string &rule, bool end_nodes) const;

    // an error with an accelerator package whose styles compute forces on
    // a device or into buffers of their own, which only LAMMPS' MD loop
    // collects (GPU, INTEL, KOKKOS): the fix's own evaluations would miss
    // them. The /omp and /opt styles are fine
    void refuse_accelerators(const char *style) const;

    // forward-communicate positions, clear forces, run the pre_force stage
    // of the other fixes, compute the contributions in mask with the given
    // energy/virial flags, reverse-communicate forces, and let the
    // force-replacing fixes act on them (project())
    void compute(int mask, int eflag, int vflag);

    // other fixes with a pre_force stage (e.g. fix omp, which prepares the
    // per-thread force arrays), and fixes that replace or project forces
    // (setforce, freeze, ...), which act on the forces at every node as
    // they do on the forces of the MD loop
    void set_hooks(const std::vector<Fix *> &prepare, const std::vector<Fix *> &project);
    bool has_projections() const { return !projections.empty(); }
    void project();    // the projections on atom->f of the owned atoms

    // potential energy of the contributions in mask as tallied by their last
    // computation with energy flags (collective call); magnitude (if given)
    // gets the sum of the absolute values of the parts
    double energy(int mask, double *magnitude = nullptr) const;

    // fraction of the system's interactions (neighbor pairs, bonds, angles,
    // dihedrals, impropers) that the contributions in mask represent;
    // collective call, recounts only after a neighbor list rebuild
    double fraction(int mask);

    // parse a contribution name (pair, bond, ..., kspace, all), 0 if unknown
    static int parse(const char *name);

    // the owned atoms whose forces compute() may change, if not all of
    // them: the first nfirst and those listed. While set, compute() clears
    // the forces of those (and of the ghosts) only, and NodeSampler::Keep
    // keeps those only (pe_jump/async: the atoms that move on fine steps)
    // (ghosts: the ghost communication of such evaluations, if not all
    // ghosts)
    struct Touched {
      int nfirst;
      const std::vector<int> *after;
      MovingGhosts *ghosts;
    };
    void only_touch(const Touched *atoms) { touched = atoms; }
    const Touched *touches() const { return touched; }

   private:
    const Touched *touched;
    void clear_forces();
    std::vector<Fix *> preparations, projections;
    Fix *omp;    // the OPENMP package's fix, if the /omp styles are in use
    void reduce_threads();
    bigint counted_at;                  // neighbor->ncalls when the counts were taken
    static constexpr int NCOUNT = 5;    // pair, bond, angle, dihedral, improper
    double count[NCOUNT];               // global number of interactions of each
    void recount();
  };

}    // namespace PEJump
}    // namespace LAMMPS_NS

#endif
