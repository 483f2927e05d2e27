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

#ifndef LMP_PE_JUMP_ATOM_STATE_H
#define LMP_PE_JUMP_ATOM_STATE_H

#include "pointers.h"

#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

namespace LAMMPS_NS {
namespace PEJump {

  // The per-atom state of a fix as one table: each field (a 3-vector or a
  // scalar per atom) is declared once with the value a new atom gets, and
  // the table grows, copies, packs (exchange and restart) and counts the
  // memory of all of them. Only owned atoms have state, so the table grows
  // with the number of owned atoms (ensure()), not with atom->nmax.

  // A fingerprint of a velocity, kept per atom to tell a velocity that
  // another fix or command changed (scaled, reversed, reset, thermostatted)
  // from the one the fix left: 53 bits of a hash of the components (-0
  // taken as 0). Odd multipliers make a change of one component change the
  // sum; the rotations keep sign flips of two components from cancelling.
  inline double velocity_fingerprint(const double *v)
  {
    static constexpr uint64_t K[3] = {0x9e3779b97f4a7c15ULL, 0xbf58476d1ce4e5b9ULL,
                                      0x94d049bb133111ebULL};
    uint64_t h = 0;
    for (int k = 0; k < 3; k++) {
      const double c = (v[k] == 0.0) ? 0.0 : v[k];
      uint64_t bits;
      memcpy(&bits, &c, sizeof(bits));
      bits = (bits << (21 * k)) | (k ? bits >> (64 - 21 * k) : 0);
      h += bits * K[k];
    }
    h ^= h >> 29;
    return static_cast<double>(h >> 11);
  }

  // A 64-bit mix of an atom ID (the finalizer of splitmix64): sets of atoms
  // told by the sum of these (modulo 2^64) collide with a chance of about
  // 2^-64; also a weight per atom that does not depend on its index
  inline uint64_t id_hash(tagint id)
  {
    uint64_t z = static_cast<uint64_t>(id) + 0x9E3779B97F4A7C15ULL;
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
    return z ^ (z >> 31);
  }

  class AtomState : protected Pointers {
   public:
    explicit AtomState(class LAMMPS *);
    ~AtomState() override;

    // a field of width 1 or 3 (values per atom); new atoms get init
    int add(const std::string &name, int width, double init);
    double **vec(int field) const { return fields[field].vec; }
    double *val(int field) const { return fields[field].val; }

    void swap(int field1, int field2);    // exchange the values of two fields of one width
    void ensure(int n);                   // room for atoms 0 .. n-1 (new room holds init values)
    void copy(int i, int j);
    void reset(int i);    // the values of a new atom
    int pack(int i, double *buf) const;
    int unpack(int i, const double *buf);
    int values() const;    // values per atom in pack() and unpack()

    // restart files: per atom the count of values, then the values; the
    // state of the nth fix with per-atom restart data of atom nlocal is
    // unpacked if its count fits (else false)
    int pack_restart(int i, double *buf) const;
    bool unpack_restart(int nlocal, int nth);
    int restart_size() const { return values() + 1; }
    double memory_usage() const;

   private:
    struct Field {
      std::string name;
      int width;
      double init;
      double **vec;
      double *val;
    };
    std::vector<Field> fields;
    int capacity;
    void grow(Field &, int from, int to);
    static void fill(Field &, int i);
  };

}    // namespace PEJump
}    // namespace LAMMPS_NS

#endif
