#!/usr/bin/env python3
"""Where a Lennard-Jones liquid cut into domains would sit at 1,000 and 10,000 ranks: a model
from what was measured here (docs/scaling.md says which figure came from where).

    python3 bench/scaling_model.py [--c NS] [--alpha US] [--beta GBS]

Per step and rank: compute c·(n + g) for n owned atoms and g ghosts (a ghost costs about as
much as an owned atom: rank 0's forces, measured, took c per local atom-step); the ghosts'
positions sent (24 bytes each) in m messages of latency alpha at beta bytes/s; two
all-reductions (the skin test and the forces' failure flag), 2·alpha·log2(P). The exchange as
built is all-to-all (m = P: MPI_Alltoall of the counts and MPI_Alltoallv of the positions,
every rank a message to every rank); with the neighbour exchange a brick grid allows, m = 26.
A checkpoint gathers every atom's position and velocity (7 numbers, 56 bytes) to rank 0 (for
the certificate's states), and every rank encloses its part of the energy and momentum over its
owned atoms and ghosts: `gather` and `judge` (per checkpoint; the cost per local atom measured on
2 ranks at 32,000 and 256,000 atoms, the gather included).
"""
import argparse
import math

RHO, HALO = 0.8442, 2.8  # in.lj's density; cut-off 2.5 plus the 0.3 skin


def model(n_atoms, ranks, c, alpha, beta, judge_per_atom, neighbours):
    n = n_atoms / ranks
    a = (n / RHO) ** (1 / 3)
    g = RHO * ((a + 2 * HALO) ** 3 - a**3)
    compute = c * (n + g)
    messages = 26 if neighbours else ranks
    talk = messages * alpha + 24 * g / beta + 2 * alpha * math.log2(ranks)
    return {
        "n": n,
        "ghosts": g / n,
        "compute_ms": compute * 1e3,
        "talk_ms": talk * 1e3,
        "efficiency": (c * n) / (compute + talk),
        "gather_s": 56 * n_atoms / beta,
        "judge_s": judge_per_atom * (n + g),
        "root_gib": 56 * n_atoms / 2**30,
    }


def main():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--c", type=float, default=154.0, help="ns per local atom-step on one core (measured: 154)")
    p.add_argument("--alpha", type=float, default=2.0, help="message latency in microseconds (assumed: 2)")
    p.add_argument("--beta", type=float, default=10.0, help="bandwidth in GB/s (assumed: 10)")
    p.add_argument("--judge", type=float, default=1.2, help="a rank's µs per local atom at a checkpoint (measured: 1.2)")
    a = p.parse_args()
    c, alpha, beta, judge = a.c * 1e-9, a.alpha * 1e-6, a.beta * 1e9, a.judge * 1e-6
    print("| atoms | ranks | atoms a rank | ghosts / owned | compute ms/step | exchange ms/step (all-to-all / 26 neighbours) "
          "| efficiency (all-to-all / neighbours) | a checkpoint: gather to rank 0 / each rank's part | rank 0 holds |")
    print("|---|---|---|---|---|---|---|---|---|")
    for n_atoms in (1e8, 1e9):
        for ranks in (1000, 10000):
            x = model(n_atoms, ranks, c, alpha, beta, judge, False)
            y = model(n_atoms, ranks, c, alpha, beta, judge, True)
            print(f"| {n_atoms:.0e} | {ranks:,} | {x['n']:,.0f} | {x['ghosts']:.2f} | {x['compute_ms']:.2f} "
                  f"| {x['talk_ms']:.2f} / {y['talk_ms']:.3f} | {x['efficiency']:.0%} / {y['efficiency']:.0%} "
                  f"| {x['gather_s']:.1f} s / {x['judge_s']:.3f} s | {x['root_gib']:.0f} GiB |")


if __name__ == "__main__":
    main()
