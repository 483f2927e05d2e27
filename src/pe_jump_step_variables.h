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

#ifndef LMP_PE_JUMP_STEP_VARIABLES_H
#define LMP_PE_JUMP_STEP_VARIABLES_H

#include <string>
#include <vector>

namespace LAMMPS_NS {
class LAMMPS;
namespace PEJump {

  // The equal- and atom-style variables whose formula reads the step
  // number: the thermo keywords step, elapsed and elaplong, the functions
  // ramp(), vdisplace(), swiggle() and cwiggle(), or another such variable
  // (v_name). Read from the formulas' text; nothing is evaluated.
  std::vector<std::string> step_number_variables(LAMMPS *);

}    // namespace PEJump
}    // namespace LAMMPS_NS

#endif
