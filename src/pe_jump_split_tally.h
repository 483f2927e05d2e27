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

#ifndef LMP_PE_JUMP_SPLIT_TALLY_H
#define LMP_PE_JUMP_SPLIT_TALLY_H

#include "pointers.h"

namespace LAMMPS_NS {
namespace PEJump {

  // The global potential energy of a node evaluated in two parts: the
  // fix evaluates one subset of the interactions there (tallied, kept()),
  // the MD step the rest (tallied by the force styles, which zero their
  // tallies first); add() puts the kept part back into the styles'
  // tallies, so that output reads the energy of all interactions at the
  // node without another evaluation. Global energy only: per-atom tallies
  // and the virial (the pair styles' f.r sum reads the forces of every
  // atom) are not split
  class SplitTally : protected Pointers {
   public:
    SplitTally(class LAMMPS *lmp) : Pointers(lmp) {}

    // at init: computes that read the tallies of single styles (compute
    // pair, bond, ...: a sub-style of a hybrid style, a pair style's
    // pvector) would see one part only, so that beside them nothing is
    // added up
    void init();
    // at the step's start
    void expect(bool yes)
    {
      wanted = yes && usable;
      held = added = false;
    }
    bool expected() const { return wanted; }
    void keep();    // after the first part's evaluation with energy flags
    bool kept() const { return held; }
    void add();    // after the second part's evaluation with energy flags
    bool complete() const { return added; }    // both parts are in the tallies

   private:
    bool usable = false, wanted = false, held = false, added = false;
    // pair (van der Waals, Coulomb), bond, angle, dihedral, improper
    static constexpr int NPART = 6;
    double energy[NPART] = {0.0, 0.0, 0.0, 0.0, 0.0, 0.0};
    double *tally(int part) const;    // the style's tally, or nullptr
  };

}    // namespace PEJump
}    // namespace LAMMPS_NS

#endif
