#!/usr/bin/env python3
"""Smoothed aggregation (PyAMG) on the systems `cargo xtask tangents` exports.

For each system in DIR/systems.csv: CG (or, for a non-symmetric system, GMRES) to the
relative residual 1e-8, at most 400 iterations, preconditioned by one V-cycle of PyAMG's
smoothed-aggregation hierarchy with the rigid-body modes as near-null space (6 in 3D,
3 in 2D, from each dof's node coordinates) and, for reference, with the translations only.
Prints one line per system beside the multigrid figures loam wrote.

    pip install pyamg          # 5.x; scipy and numpy come with it
    cargo xtask tangents --out target/tangents
    python3 scripts/compare_preconditioners.py target/tangents
"""
import csv
import sys
import time

import numpy as np
import pyamg
import scipy.sparse as sp

TOL = 1e-8
MAXITER = 400


def load(base):
    colptr = np.fromfile(base + ".colptr", dtype="<i8")
    rowidx = np.fromfile(base + ".rowidx", dtype="<i4")
    values = np.fromfile(base + ".values", dtype="<f8")
    rhs = np.fromfile(base + ".rhs", dtype="<f8")
    coords = np.fromfile(base + ".coords", dtype="<f8").reshape(-1, 4)
    n = len(rhs)
    a = sp.csc_matrix((values, rowidx, colptr), shape=(n, n)).tocsr()
    return a, rhs, coords


def near_null_space(coords, d, rotations):
    """Translations, and with `rotations` the infinitesimal rotations about the centre."""
    x = coords[:, :3] - coords[:, :3].mean(axis=0)
    comp = coords[:, 3].astype(int)
    modes = [(comp == k).astype(float) for k in range(d)]
    if rotations:
        # Rotation about axis (i, j): u_i = -x_j, u_j = x_i.
        planes = [(0, 1)] if d == 2 else [(0, 1), (1, 2), (0, 2)]
        for i, j in planes:
            m = np.zeros(len(comp))
            m[comp == i] = -x[comp == i, j]
            m[comp == j] = x[comp == j, i]
            modes.append(m)
    return np.column_stack(modes)


def solve(a, b, coords, d, rotations, symmetric):
    t = time.perf_counter()
    ml = pyamg.smoothed_aggregation_solver(
        a,
        B=near_null_space(coords, d, rotations),
        symmetry="symmetric" if symmetric else "nonsymmetric",
        max_coarse=400,
    )
    setup = time.perf_counter() - t
    residuals = []
    t = time.perf_counter()
    x = ml.solve(b, tol=TOL, maxiter=MAXITER, accel="cg" if symmetric else "gmres", residuals=residuals)
    elapsed = time.perf_counter() - t
    rel = np.linalg.norm(b - a @ x) / np.linalg.norm(b)
    its = len(residuals) - 1
    return its, rel, setup, elapsed, ml.operator_complexity(), len(ml.levels)


def main(folder):
    with open(folder + "/systems.csv") as f:
        rows = list(csv.DictReader(f))
    print("system | dofs | loam GMG: its to 1e-8 (set-up s, solve s) | SA + rigid-body modes: its, residual (set-up s, solve s), op. complexity, levels | SA + translations: its, residual")
    for row in rows:
        name = row["system"]
        a, b, coords = load(folder + "/" + name)
        d = int(row["dofs per node"])
        asym = abs(a - a.T).max() / abs(a).max()
        symmetric = asym < 1e-10
        full = solve(a, b, coords, d, True, symmetric)
        plain = solve(a, b, coords, d, False, symmetric)
        print(
            f"{name} | {len(b)} | {row['iterations to 1e-8']} ({row['set-up s']}, {row['solve s']}) | "
            f"{full[0]}, {full[1]:.1e} ({full[2]:.3f}, {full[3]:.3f}), {full[4]:.2f}, {full[5]} | "
            f"{plain[0]}, {plain[1]:.1e}"
        )


if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else "target/tangents")
