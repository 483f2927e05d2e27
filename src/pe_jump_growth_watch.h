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

#ifndef LMP_PE_JUMP_GROWTH_WATCH_H
#define LMP_PE_JUMP_GROWTH_WATCH_H

namespace LAMMPS_NS {
namespace PEJump {

  // Watches the share of the jump energy in the kinetic energy for a slow
  // growth: a weak resonance of the two clocks pumps the jumps by a
  // fraction of a percent per coarse step, and the stability guard stops
  // the run only once they are large. The share (jump energy over
  // pseudo-kinetic plus jump energy, i.e. over (1/2) sum m |v|^2) is summed
  // over windows of WINDOW samples; growth() is true once a window's share
  // exceeds both MIN_SHARE and FACTOR times the largest share of the
  // windows up to LAG windows before it. The first window, where the jumps
  // build up from the start, is no reference; the lag lets a growth of
  // less than FACTOR per window add up.
  //
  // Calibrated on the paper's inhomogeneous wave (20000 coarse steps,
  // N = 250 to 1000, h_S = 0.3 to 0.9 dx, K = 5 to 20, buffer 0 and 1):
  // in the stable runs a window's share is at most 1.11 times its
  // reference. The resonances (0.66 % amplitude growth per coarse step
  // and the slower ones of N = 500, 0.3 dx and N = 1000, 0.4 dx) pass it
  // 500, 3000 and 2250 coarse steps before the guard stops the run. A
  // share below MIN_SHARE is no danger and may grow for physical reasons
  // (a pulse entering a stiffer region)
  class GrowthWatch {
   public:
    static constexpr int EVERY = 10;     // coarse steps between samples
    static constexpr int WINDOW = 25;    // samples per window
    static constexpr int LAG = 2;        // windows
    static constexpr double FACTOR = 2.0;
    static constexpr double MIN_SHARE = 0.1;

    void restart();    // a run starts
    // one sample: the pseudo-kinetic and the jump energy (TwoStep::energies)
    void sample(double pseudo_kinetic, double jump);
    bool growth() const { return grown; }
    double reference_share() const { return reference; }
    double latest_share() const { return latest; }

   private:
    int samples = 0, windows = 0;
    double jump_sum = 0.0, kinetic_sum = 0.0;
    double reference = 0.0, latest = 0.0;
    double recent[LAG] = {0.0, 0.0};    // the last LAG windows' shares
    bool grown = false;
  };

}    // namespace PEJump
}    // namespace LAMMPS_NS

#endif
