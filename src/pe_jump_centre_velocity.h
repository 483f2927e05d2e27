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

#ifndef LMP_PE_JUMP_CENTRE_VELOCITY_H
#define LMP_PE_JUMP_CENTRE_VELOCITY_H

#include "pe_jump_atom_set.h"

namespace LAMMPS_NS {
namespace PEJump {

  // The velocities that other fixes see where the impulse of their forces
  // sits inside the step (midpoint and Legendre rules: position Verlet for
  // those forces). The free flight there is the velocity before the
  // impulse; a force that depends on it (the drag of fix langevin or fix
  // viscous) would act as in an explicit Euler step, and fix langevin's
  // stationary temperature would come out high by h/(2 damp). The fixes see
  // instead the free flight plus half the impulse of the last step (half):
  // an explicit estimate of the mean of the velocities before and after
  // this step's impulse, as the trapezoidal rule takes a drag.
  struct CentreVelocity {
    // v += half for the atoms of set; kept: v before
    static void show(const AtomSet &set, const int *mask, int nlocal, double **v, double **half,
                     double **kept)
    {
      set.each(mask, nlocal, [&](int i) {
        for (int k = 0; k < 3; k++) {
          kept[i][k] = v[i][k];
          v[i][k] += half[i][k];
        }
      });
    }

    // v = kept again where v is still kept + half: a velocity that another
    // fix changed meanwhile stays as that fix left it, for the check of
    // velocity changes inside the step to see
    static void take_back(const AtomSet &set, const int *mask, int nlocal, double **v,
                          double **half, double **kept)
    {
      set.each(mask, nlocal, [&](int i) {
        for (int k = 0; k < 3; k++)
          if (v[i][k] == kept[i][k] + half[i][k]) v[i][k] = kept[i][k];
      });
    }
  };

}    // namespace PEJump
}    // namespace LAMMPS_NS

#endif
