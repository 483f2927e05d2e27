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

#ifndef LMP_PE_JUMP_INTERACTION_SPLIT_H
#define LMP_PE_JUMP_INTERACTION_SPLIT_H

#include "pointers.h"

#include <utility>
#include <vector>

namespace LAMMPS_NS {
class NeighList;
namespace PEJump {

  // Splits the interactions of the force field (pairs of the pair styles'
  // neighbor lists, bonds, angles, dihedrals, impropers) by the clocks of
  // the atoms they involve: an interaction that involves an atom on the
  // fine clock belongs to the FINE subset, every other one (only atoms on
  // the coarse clock, or atoms that are not integrated) to the COARSE
  // subset. While a subset is active, the neighbor lists of the pair styles
  // and the topology lists of the neighbor class hold only its interactions,
  // so that the force styles compute only those.

  class InteractionSplit : protected Pointers {
   public:
    // ALL: the complete lists, for a complete evaluation after subsets were
    // active (hybrid bonded styles then sort their sub-style lists again)
    enum Subset { FINE = 0, COARSE = 1, NONE = 2, ALL = 3 };

    InteractionSplit(class LAMMPS *, int groupbit, int finebit);
    ~InteractionSplit() override;

    // the atoms on the fine clock: those of the group with this group bit
    void set_fine_bit(int bit) { finebit = bit; }

    // 1 if atom i (owned or ghost) is integrated on the fine clock
    int fine(int i) const;
    // 1 if atom i (owned or ghost) is integrated on the coarse clock
    int coarse(int i) const;

    // build both subsets from the current neighbor and topology lists;
    // collective call, after every neighbor list build
    void build();
    bool up_to_date() const;                // built from the current lists
    void invalidate() { built_at = -1; }    // the clocks changed: build again

    // the classes of the interactions hold for a whole run: the number of
    // bonds, angles, dihedrals and impropers must not change (fix
    // bond/create, bond/break, ...). start_run() at init, then check
    void start_run();
    void check_topology() const;

    // swap the lists of one subset in, and the complete lists back
    void activate(Subset);
    void restore();
    Subset active() const { return current; }

    // whether the pair style can be split pair by pair (collective):
    // evaluated once with empty lists it must give no force (OFF_LISTS: a
    // style with partner lists of its own, e.g. peri), and evaluated with
    // each list cut to one pair (the closest for each atom type) no force
    // on other atoms than the two of the pair (OFF_PAIRS: a hydrogen bond
    // style acts on the hydrogen, TIP4P styles on the atoms of both
    // molecules), and with every list cut to one pair the same forces at
    // later steps of the run (ON_TIME: hybrid/scaled with a variable of
    // time or step, which the fine and coarse nodes would see at the step
    // end), and the forces of two pairs of an atom the sum of the forces of
    // each (NOT_ADDITIVE: a many-body style that does not say so, e.g.
    // local/density, whose pair forces depend on the atoms' densities)
    enum PairFit { FITS, OFF_PAIRS, OFF_LISTS, ON_TIME, NOT_ADDITIVE };
    PairFit pair_fit();

    // fraction of all interactions that a subset holds (global)
    double fraction(Subset which) const { return frac[which]; }

    // flag[i] = 1 for every atom i (owned or ghost) on the fine clock that
    // shares an interaction with an atom on the coarse clock: a bonded one,
    // or a pair closer than the pair style's cutoff
    void mark_interface(std::vector<int> &flag) const;

    // flag[i] = 1 for every atom i (owned or ghost) that takes part in an
    // interaction of the FINE subset (a pair of its lists, a bond, ...)
    void mark_fine_participants(std::vector<int> &flag) const { mark_fine(flag, false); }

    // the same for the interactions of the FINE subset that act at the
    // current positions: bonded ones, and pairs closer than the pair
    // style's cutoff (not those within the skin only), so that the result
    // does not depend on when the lists were built; with reach > 0 only
    // pairs closer than reach (bonded ones whatever their length)
    void mark_fine_partners(std::vector<int> &flag, double reach = 0.0) const
    {
      mark_fine(flag, true, reach);
    }

   private:
    int groupbit, finebit;
    Subset current;
    // hybrid bonded styles sort the topology lists into sub-style lists only
    // at a neighbor list build (neighbor->ago == 0): while a subset is
    // active, ago reads 0 so that they sort the subset
    int hybrid_topology;
    int saved_ago;
    double frac[2];
    bigint built_at;    // neighbor->ncalls at the last build
    bigint topology;    // bonds, angles, ... when the run started
    bigint topology_count() const;

    // one pair neighbor list, its original arrays and both subsets
    struct PairSubset {
      std::vector<int> ilist;    // the atoms with neighbors in the subset
      std::vector<int> numneigh;
      std::vector<int *> firstneigh;    // into PairList::neigh
    };
    struct PairList {
      NeighList *list = nullptr;
      int inum = 0;
      int *ilist = nullptr;
      int *numneigh = nullptr;
      int **firstneigh = nullptr;
      PairSubset part[2];
      std::vector<int> neigh;    // the neighbors of both subsets
    };
    std::vector<PairList> pairs;
    std::vector<std::pair<int, int>> probe_pairs(const NeighList *) const;    // (i, jj)
    bool forces_off_lists();       // pair_fit(): forces with every list empty
    bool forces_off_pairs();       // pair_fit(): forces beyond one pair per type
    bool depends_on_time();        // pair_fit(): the pair style, on one pair per list
    bool additive(NeighList *);    // pair_fit(): two pairs of one atom of the list
    std::vector<int> cross;        // pairs (i,j) of a fine and a coarse atom
    std::vector<int> clock_of;     // work: per atom 1 fine clock, 2 coarse clock, 0 neither

    // one topology list (bonds, angles, ...) of the neighbor class, whose
    // entries are reordered in place: the FINE ones first, then the COARSE
    // ones, so that either subset is a contiguous part of the list (as the
    // /omp styles, which read it as one array, require)
    struct TopoList {
      int on;    // the style exists, so that the neighbor class builds this list
      int *count;
      int ***list;
      int natoms;    // atoms per entry
      int nfull;     // entries of the complete list
      int **full;    // the complete list
      int nfine;     // entries of the FINE subset
    };
    std::vector<int> coarse_entries;    // work: entries moved behind the fine ones
    TopoList topo[4];

    void mark_fine(std::vector<int> &flag, bool acting, double reach = 0.0) const;
    // closer than the pair style's cutoff, and than reach if > 0
    bool within_cutoff(int i, int j, double reach = 0.0) const;    // needs a pair style
    void split_pairs(PairList &);
    void label_clocks();    // clock_of for the owned and ghost atoms
    int sort_neighbors(int i, const int *jlist, int n, int *fine_at, int *coarse_end);
    void split_topology(TopoList &);
  };

}    // namespace PEJump
}    // namespace LAMMPS_NS

#endif
