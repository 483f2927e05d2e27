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

#ifndef LMP_PE_JUMP_ASYNC_CLOCKS_H
#define LMP_PE_JUMP_ASYNC_CLOCKS_H

#include "pe_jump_node_sampler.h"

namespace LAMMPS_NS {
namespace PEJump {
  class AtomState;

  // The clocks of pe_jump/async: K fine steps make a coarse step, and all
  // times are times within the current coarse step. The atoms that move
  // with the fine steps are at now(); a slow atom that takes part in no
  // fine interaction sits out the fine steps at the time its position
  // belongs to (per atom, a field of the state table) and catches up with
  // its free flight when it is needed.

  class AsyncClocks : protected Pointers {
   public:
    static constexpr double MOVING = -1.0;    // per-atom time of an atom that moves

    AsyncClocks(class LAMMPS *, AtomState &, int nfine);

    int steps() const { return nfine; }
    int done() const { return fine; }    // fine steps done in this coarse step
    bool at_coarse_node() const { return fine == 0; }
    bool last_fine_step() const { return fine + 1 >= nfine; }
    bool next_is_last() const { return fine + 2 >= nfine; }    // inside a fine step
    double start() const { return elapsed; }    // time at the start of this fine step
    double now() const { return tnow; }         // time of the atoms that move

    void begin_coarse();                 // a new coarse step, at its start (atoms caught up)
    void moving_at(double t);            // the moving atoms went on to start() + t
    void end_fine(double h);             // a fine step of size h ended
    bool restore(const double *list);    // restart data (K, fine steps, time): K the same?
    void save(double *list) const;

    // per atom: its time (MOVING if it moves with the fine steps), hold it
    // at now(), catch it up to now() with free-flight velocity v (it then
    // moves if moving)
    double *times() const;
    void hold(int i);
    void catch_up(int i, const FreeFlight &v, bool moving);
    void catch_up_all(const FreeFlight &v, const int *moving);

   private:
    AtomState &state;
    int TIME;    // state field
    int nfine, fine;
    double elapsed, tnow;
  };

}    // namespace PEJump
}    // namespace LAMMPS_NS

#endif
