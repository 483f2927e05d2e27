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

#ifndef LMP_PE_JUMP_TWO_CLOCKS_H
#define LMP_PE_JUMP_TWO_CLOCKS_H

namespace LAMMPS_NS {
namespace PEJump {

  // The fine and the coarse clock of pe_jump/async: where they are inside
  // one coarse step, which is one MD step. The coarse step H (the MD time
  // step) holds K fine steps of h = H / K. The atoms that move on fine
  // steps have done done() of them and are into() the next; the slow atoms
  // outside fine interactions are held at held() (times from the coarse
  // step's start). Times inside the coarse step are counted in fine steps
  // where they are compared, so that a node at K/2 fine steps is one
  // whatever the rounding of H / K.

  class TwoClocks {
   public:
    explicit TwoClocks(int nfine) : nfine(nfine) {}

    int steps() const { return nfine; }
    void begin(double coarse_step)    // the coarse step begins: nothing done
    {
      coarse = coarse_step;
      fine = 0;
      into_fine = 0.0;
      held_at = 0.0;
    }
    double coarse_step() const { return coarse; }
    double fine_step() const { return coarse / nfine; }
    int done() const { return fine; }
    double into() const { return into_fine; }    // time into the current fine step
    double held() const { return held_at; }

    // the moving atoms are at u fine steps from the coarse step's start,
    // inside the fine step they are in
    void moved_to(double u) { into_fine = (u - fine) * fine_step(); }
    void fine_step_done()
    {
      ++fine;
      into_fine = 0.0;
    }
    void hold_at(double t) { held_at = t; }

   private:
    int nfine;
    double coarse = 0.0;
    int fine = 0;
    double into_fine = 0.0, held_at = 0.0;
  };

}    // namespace PEJump
}    // namespace LAMMPS_NS

#endif
