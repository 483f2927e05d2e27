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

#ifndef LMP_PE_JUMP_OPTIONS_H
#define LMP_PE_JUMP_OPTIONS_H

namespace LAMMPS_NS {
class LAMMPS;

namespace PEJump {

  // The keywords of fix pe_jump and fix pe_jump/async (see their
  // documentation) with their defaults
  struct Options {
    enum Init { KICK, PAPER };

    int family;    // Quadrature::Family of the rule
    int npoints;
    int init_style;
    int sample_mask;    // ForceSampler contributions sampled at the nodes
    double auto_tol;    // quadrature auto: defect tolerance, 0 if not auto
    double adapt_eps, adapt_dtmin, adapt_dtmax;    // adapt: eps 0 if off
    int compensate;                                // -1: on with adapt
    double damp_time;                              // -1: auto
    int buffer_layers;                             // pe_jump/async only
    double buffer_reach;    // buffer pairs closer than this (0: the pair cutoff)
    double fast_auto;       // pe_jump/async fast auto: fraction of the skin, 0 if off

    Options();

    // parse arg[first .. narg-1] of fix style; the buffer keyword only
    // with two clocks (pe_jump/async)
    void parse(LAMMPS *, const char *style, int narg, char **arg, int first, bool two_clocks);

   private:
    int quadrature(LAMMPS *, const char *style, int narg, char **arg, int iarg);
    int sample(LAMMPS *, const char *style, int narg, char **arg, int iarg);
    int clock_keyword(LAMMPS *, const char *style, int narg, char **arg, int iarg);
  };

}    // namespace PEJump
}    // namespace LAMMPS_NS

#endif
