#!/usr/bin/env python3
"""Stationary temperature of one harmonic mode under fix langevin with
fix pe_jump, computed exactly (no sampling) from the linear step map.

The mode has frequency omega and unit mass, kT = 1. One step of fix
pe_jump beside fix langevin (friction gamma, step h) is written as
X_{n+1} = A X_n + b xi_n on the state (q^n, node velocity v^n, jump
[v]^n, the Langevin force of the last step, and the damping's kept d and
P), exactly as the fix does it: midpoint takes the Langevin force at the
centre of the step with the free-flight velocity and applies it there
(fix pe_jump); "midpoint, centre velocity" takes it there with the free
flight plus half the last step's Langevin impulse (fix pe_jump/async,
CentreVelocity); Lobatto rules take it at the step end and apply it half
before and half after the node (velocity Verlet). The stationary covariance solves the
discrete Lyapunov equation S = A S A^T + b b^T; the printed temperature
is S[v, v] (1 = exact). The pulls of the damping:
  own impulse  [v]^{n+1} = (2 - beta) h <a> - (1 - beta) [v]^n (earlier)
  (3P - P')/4  the fixes now (doc/theory.md, section 3.0)

usage: langevin_harmonic.py [h [gamma]]   (default 0.012 0.1: bench/in.chain)"""
import sys
import warnings

import numpy as np
from scipy.linalg import solve_discrete_lyapunov

PULLS = {
    "own impulse": lambda J, d, P, Pl: J - d / 2,
    "(3P - P')/4": lambda J, d, P, Pl: (3 * P - Pl) / 4,
}


def step(rule, omega, h, gamma, beta, pull, s, xi):
    q, u, J, rlast, dlast, plast = s
    acc = lambda x: -omega * omega * x
    if rule.startswith("midpoint"):
        vh = u + J / 2
        qm = q + 0.5 * h * vh
        seen = vh + 0.5 * h * rlast if rule == "midpoint, centre velocity" else vh
        r = -gamma * seen + np.sqrt(2 * gamma / h) * xi
        avg = acc(qm)
        vh = vh + h * r
        q1 = qm + 0.5 * h * vh
    else:
        vh = u + J / 2 + 0.5 * h * rlast
        qm, q1 = q + 0.5 * h * vh, q + h * vh
        r = -gamma * vh + np.sqrt(2 * gamma / h) * xi
        vh = vh + 0.5 * h * r
        avg = (acc(q) + 4 * acc(qm) + acc(q1)) / 6 if rule == "lobatto 3" else \
            (acc(q) + acc(q1)) / 2
    d = 2 * h * avg
    P = J - (dlast + d) / 4
    Jn = d - J + (beta * PULLS[pull](J, d, P, plast) if beta > 0 else 0.0)
    return np.array([q1, vh + Jn / 2, Jn, r, d, P])


def temperature(rule, omega, h, gamma, beta, pull):
    n = 6
    a = np.column_stack([step(rule, omega, h, gamma, beta, pull, e, 0.0) for e in np.eye(n)])
    b = step(rule, omega, h, gamma, beta, pull, np.zeros(n), 1.0)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return solve_discrete_lyapunov(a, np.outer(b, b))[1, 1]


def main():
    h = float(sys.argv[1]) if len(sys.argv) > 1 else 0.012
    gamma = float(sys.argv[2]) if len(sys.argv) > 2 else 0.1
    print(f"h = {h}, gamma = {gamma}, damp auto (beta = 1e-3): stationary T of one mode")
    print("| rule | h omega | own impulse | (3P - P')/4 |")
    print("|---|---|---|---|")
    for rule in ["midpoint", "midpoint, centre velocity", "lobatto 3"]:
        for theta in [0.06, 0.24, 0.48, 0.96]:
            cells = [f"{temperature(rule, theta / h, h, gamma, 1e-3, p):.5f}" for p in PULLS]
            print(f"| {rule} | {theta} | " + " | ".join(cells) + " |")


if __name__ == "__main__":
    main()
