#!/usr/bin/env python3
"""Linear analysis of the damping of the parasitic mode of fix pe_jump.

One harmonic mode of frequency omega, midpoint rule, constant step h. The
step map acts on (q^n, v^{n+1/2}, [v]^n, d_{n-1}, P^{n-1}) with
d_n = 2 h <a>_n and P^n = [v]^n - (d_{n-1} + d_n)/4; a damped step takes
[v]^{n+1} = d_n - [v]^n + beta X^n. Printed: the largest modulus of the
eigenvalues less 1 (growth per step of the smooth mode; negative: it
decays) for three pulls X^n, and the modulus of the alternating mode.

  X = [v]^n - d_n/2        towards the step's own impulse (earlier fixes)
  X = P^n                  centred on the node
  X = (3 P^n - P^{n-1})/4  centred where the jump acts (the fixes now)

usage: damping_spectrum.py [beta]   (default 0.001, as damp auto)"""
import sys

import numpy as np

PULLS = {
    "own impulse": lambda jmp, d, P, Pp: jmp - d / 2,
    "node": lambda jmp, d, P, Pp: P,
    "(3P - P')/4": lambda jmp, d, P, Pp: (3 * P - Pp) / 4,
}


def step_matrix(omega, h, beta, pull):
    m = np.zeros((5, 5))
    for c in range(5):
        q, vh, jmp, dlast, plast = np.eye(5)[c]
        a = -omega * omega * (q + 0.5 * h * vh)    # force at the midpoint node
        d = 2 * h * a
        P = jmp - (dlast + d) / 4
        jnew = d - jmp + beta * pull(jmp, d, P, plast)
        m[:, c] = [q + h * vh, vh + jnew, jnew, d, P]
    return m


def main():
    beta = float(sys.argv[1]) if len(sys.argv) > 1 else 1e-3
    h = 1.0
    print(f"beta = {beta}: growth per step of the smooth mode (|lambda| - 1)")
    print("| h omega | " + " | ".join(PULLS) + " | alternating mode |")
    print("|---|" + "---|" * (len(PULLS) + 1))
    for theta in [0.1, 0.2, 0.3, 0.5, 0.8, 1.2, 1.6]:
        cells = []
        for pull in PULLS.values():
            ev = np.abs(np.linalg.eigvals(step_matrix(theta / h, h, beta, pull)))
            cells.append(f"{ev.max() - 1:.2e}")
        ev = np.sort(np.abs(np.linalg.eigvals(step_matrix(theta / h, h, beta,
                                                          PULLS["(3P - P')/4"]))))
        cells.append(f"{ev[-3]:.6f}")
        print(f"| {theta} | " + " | ".join(cells) + " |")


if __name__ == "__main__":
    main()
