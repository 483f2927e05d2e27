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

#ifndef LMP_PE_JUMP_ERRORS_H
#define LMP_PE_JUMP_ERRORS_H

#include "utils.h"

#include <string>

namespace LAMMPS_NS {
namespace PEJump {

  // As LAMMPS' utils::errorurl(): the link to the section of
  // doc/Errors_pe_jump.rst that explains an error or a warning, appended
  // to its one-line message, e.g.
  //
  //   error->all(FLERR, "Fix {}: ...{}", style, ..., PEJump::errorurl(3));
  //
  // The section of code N has the label ".. _pejump_errNN:" (two digits),
  // whose HTML id Sphinx makes "pejump-errNN". Codes are never reused or
  // renumbered; a new section gets the next free code. The ctest
  // PEJump.ErrorLinksResolve (tools/check_error_links.py) fails if a code
  // used in src/ has no section.

  inline std::string errorurl(int code)
  {
    return fmt::format("; see doc/Errors_pe_jump.rst#pejump-err{:02d}", code);
  }

}    // namespace PEJump
}    // namespace LAMMPS_NS

#endif
