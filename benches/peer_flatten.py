#!/usr/bin/env python3
"""Peer comparison of grade3d's panel flattening with libigl's LSCM and ARAP.

Rerun with:

    pip install libigl numpy
    cargo build --release && target/release/grade3d panels      # writes target/panels/*.obj
    python3 benches/peer_flatten.py [--panels DIR] [--grade3d PATH] [--repeat N] [--json-out FILE]

For every OBJ panel in --panels (a triangulated disc) it runs

* ours: ``grade3d flatten <panel.obj> --json`` (LSCM start, then ARAP with
  exact boundary lengths; timings measured inside the binary, best of
  --repeat runs);
* libigl (PyPI ``libigl``): ``igl.lscm`` with the same two pins (the boundary
  vertices farthest apart in 3D, at (0, 0) and (d, 0), d their 3D distance),
  then ``igl.arap_precomputation`` + ``igl.arap_solve`` (per-triangle
  rotations, ARAP_ENERGY_TYPE_ELEMENTS = Liu et al. 2008) from that LSCM
  start, holding the first pin at the origin, for the same number of
  iterations as ours took (timed in this process, best of --repeat runs);

and prints one table: time (ms), the time ratio ours/libigl, and the
distortion figures, all computed here by one numpy implementation of the
definitions of ``grade3d::pattern::flatten::distortion`` (Wang, Smith & Yuen
2002: E_s = (A - A')/A, E_c = (L - L')/L; per-unique-edge strain |l'/l - 1|,
its 95th percentile by nearest rank and its maximum; flipped triangles after
orienting the map so that its total signed area is positive; boundary length
error (B' - B)/B). Our own figures, as printed by the binary, are checked
against the numpy ones.
"""

import argparse
import importlib.metadata
import json
import math
import pathlib
import subprocess
import sys
import time

import numpy as np

try:
    import igl
except ImportError:  # pragma: no cover - message for people without libigl
    sys.exit("libigl is missing: pip install libigl numpy")

PLAIN = False  # set from --plain
PIN_TIE = 1e-9  # FlattenOptions::pin_tie: pairs this close to the largest distance are ties
P95 = 0.95


def read_obj(path):
    """Vertices (n x 3 float64) and triangles (m x 3 int64) of an OBJ file; polygons are fanned."""
    verts, faces = [], []
    with open(path, encoding="utf-8") as f:
        for line in f:
            w = line.split()
            if not w:
                continue
            if w[0] == "v":
                verts.append([float(x) for x in w[1:4]])
            elif w[0] == "f":
                idx = [int(x.split("/")[0]) for x in w[1:]]
                idx = [i - 1 if i > 0 else len(verts) + i for i in idx]
                for k in range(1, len(idx) - 1):
                    faces.append([idx[0], idx[k], idx[k + 1]])
    return np.array(verts, dtype=np.float64), np.array(faces, dtype=np.int64)


def pins(V, F):
    """The two boundary vertices farthest apart in 3D, ties (within PIN_TIE) to the lowest pair."""
    ring = np.asarray(igl.boundary_loop(F), dtype=np.int64)
    P = V[ring]
    d2 = ((P[:, None, :] - P[None, :, :]) ** 2).sum(axis=2)
    i, j = np.triu_indices(len(ring), k=1)
    d2 = d2[i, j]
    most = d2.max()
    floor = most * max(1.0 - PIN_TIE, 0.0) ** 2
    a, b = np.minimum(ring[i], ring[j]), np.maximum(ring[i], ring[j])
    cand = np.flatnonzero(d2 >= floor)
    best = cand[np.lexsort((b[cand], a[cand]))[0]]
    return int(a[best]), int(b[best]), math.sqrt(d2[best])


def distortion(V, F, UV):
    """The figures of grade3d::pattern::flatten::distortion, same definitions."""
    n = min(len(V), len(UV))
    F = F[(F < n).all(axis=1)]
    a, b, c = V[F[:, 0]], V[F[:, 1]], V[F[:, 2]]
    area3 = 0.5 * np.linalg.norm(np.cross(b - a, c - a), axis=1).sum()
    p, q, r = UV[F[:, 0]], UV[F[:, 1]], UV[F[:, 2]]
    e1, e2 = q - p, r - p
    signed = 0.5 * (e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0])
    orient = -1.0 if signed.sum() < 0 else 1.0
    flipped = int((orient * signed <= 0).sum())
    area2 = np.abs(signed).sum()
    E = np.concatenate([F[:, [0, 1]], F[:, [1, 2]], F[:, [2, 0]]])
    E = E[E[:, 0] != E[:, 1]]
    E = np.sort(E, axis=1)
    E, count = np.unique(E, axis=0, return_counts=True)
    l3 = np.linalg.norm(V[E[:, 0]] - V[E[:, 1]], axis=1)
    l2 = np.linalg.norm(UV[E[:, 0]] - UV[E[:, 1]], axis=1)
    ok = l3 > 0
    strain = np.sort(np.abs(l2[ok] / l3[ok] - 1.0))
    m = len(strain)
    bnd = count == 1
    b3, b2 = l3[bnd].sum(), l2[bnd].sum()
    bstrain = np.abs(l2[bnd & ok] / l3[bnd & ok] - 1.0)
    ratio = lambda x, y: (x - y) / x if x > 0 else 0.0  # noqa: E731
    return {
        "area_accuracy": ratio(area3, area2),
        "length_accuracy": ratio(l3.sum(), l2.sum()),
        "strain_mean": float(strain.mean()) if m else 0.0,
        "strain_p95": float(strain[min(max(math.ceil(P95 * m), 1), m) - 1]) if m else 0.0,
        "strain_max": float(strain[-1]) if m else 0.0,
        "flipped": flipped,
        "boundary_length_error": (b2 - b3) / b3 if b3 > 0 else 0.0,
        "boundary_strain_max": float(bstrain.max()) if len(bstrain) else 0.0,
    }


def run_ours(binary, path, repeat):
    best = None
    for _ in range(repeat):
        cmd = [str(binary), "flatten", str(path), "--json"] + (["--plain"] if PLAIN else [])
        out = subprocess.run(cmd, capture_output=True, text=True)
        if out.returncode != 0:
            raise RuntimeError(f"{binary} flatten {path}: {out.stderr.strip() or out.stdout.strip()}")
        r = json.loads(out.stdout)
        if best is None or r["total_ms"] < best["total_ms"]:
            best = r
    best["uv"] = np.array(best["uv"], dtype=np.float64).reshape(-1, 2)
    return best


def run_libigl(V, F, iterations, repeat):
    p0, p1, d = pins(V, F)
    b_lscm = np.array([p0, p1], dtype=np.int64)
    bc_lscm = np.array([[0.0, 0.0], [d, 0.0]])
    b_arap = np.array([p0], dtype=np.int32)
    bc_arap = np.zeros((1, 2))
    best = None
    for _ in range(repeat):
        t0 = time.perf_counter()
        start, _ = igl.lscm(V, F, b_lscm, bc_lscm)
        t1 = time.perf_counter()
        data = igl.ARAPData()
        data.energy = igl.ARAP_ENERGY_TYPE_ELEMENTS
        data.with_dynamics = False
        data.max_iter = max(int(iterations), 1)
        igl.arap_precomputation(V, F, 2, b_arap, data)
        uv = igl.arap_solve(bc_arap, data, np.array(start))
        t2 = time.perf_counter()
        r = {"lscm_ms": (t1 - t0) * 1e3, "arap_ms": (t2 - t1) * 1e3, "total_ms": (t2 - t0) * 1e3}
        if best is None or r["total_ms"] < best["total_ms"]:
            best = dict(r, lscm_uv=np.asarray(start), uv=np.asarray(uv), iterations=data.max_iter)
    return best


def fmt(x, spec):
    return format(x, spec) if isinstance(x, (int, float)) else str(x)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--panels", default="target/panels/", help="folder of OBJ panels (default target/panels/)")
    ap.add_argument("--grade3d", default="target/release/grade3d", help="the grade3d binary")
    ap.add_argument("--repeat", type=int, default=5, help="runs per panel and method; the fastest counts (default 5)")
    ap.add_argument("--json-out", help="also write every figure to this JSON file")
    ap.add_argument(
        "--plain",
        action="store_true",
        help="run ours as plain ARAP (grade3d flatten --plain: no boundary springs, no seam truing), like libigl's",
    )
    args = ap.parse_args()
    global PLAIN
    PLAIN = args.plain

    panels = sorted(pathlib.Path(args.panels).glob("*.obj"))
    if not panels:
        sys.exit(f"no OBJ panels in {args.panels}")
    binary = pathlib.Path(args.grade3d)
    if not binary.exists():
        sys.exit(f"{binary} not found: cargo build --release, or pass --grade3d PATH")

    cols = [
        ("panel", 24, "s"), ("method", 13, "s"), ("V", 6, "d"), ("F", 6, "d"), ("it", 4, "d"),
        ("ms", 8, ".2f"), ("ours/igl", 8, ".2f"), ("p95", 9, ".2e"), ("max", 9, ".2e"),
        ("E_s", 10, "+.2e"), ("E_c", 10, "+.2e"), ("boundary", 10, "+.2e"), ("flips", 5, "d"),
    ]
    head = "  ".join(f"{name:>{w}}" if spec != "s" else f"{name:<{w}}" for name, w, spec in cols)
    try:
        version = importlib.metadata.version("libigl")
    except importlib.metadata.PackageNotFoundError:
        version = "?"
    print(f"{binary} vs libigl {version}; best of {args.repeat} runs; strain = |l'/l - 1|; boundary = (B' - B)/B")
    print(head)
    print("-" * len(head))
    results = []
    for path in panels:
        V, F = read_obj(path)
        try:
            ours = run_ours(binary, path, args.repeat)
        except RuntimeError as e:
            print(f"{path.stem:<24}  ours failed: {e}")
            continue
        dv = distortion(V, F, ours["uv"])
        for key, value in ours["distortion"].items():
            if key in dv and abs(dv[key] - value) > 1e-9 * max(1.0, abs(value)):
                print(f"  warning: {path.stem}: {key} is {value} in the binary, {dv[key]} here", file=sys.stderr)
        igl_r = run_libigl(V, F, ours["iterations"], args.repeat)
        dl, da = distortion(V, F, igl_r["lscm_uv"]), distortion(V, F, igl_r["uv"])
        rows = [
            ("grade3d", ours["iterations"], ours["total_ms"], ours["total_ms"] / igl_r["total_ms"], dv),
            ("libigl ARAP", igl_r["iterations"], igl_r["total_ms"], "", da),
            ("libigl LSCM", 0, igl_r["lscm_ms"], ours["lscm_ms"] / igl_r["lscm_ms"], dl),
        ]
        for k, (method, it, ms, ratio, d) in enumerate(rows):
            vals = [
                path.stem if k == 0 else "", method, len(V), len(F), it, ms, ratio, d["strain_p95"],
                d["strain_max"], d["area_accuracy"], d["length_accuracy"], d["boundary_length_error"], d["flipped"],
            ]
            print("  ".join(
                f"{fmt(v, spec):<{w}}" if spec == "s" else f"{fmt(v, spec):>{w}}" for v, (_, w, spec) in zip(vals, cols)
            ))
        results.append({
            "panel": path.name, "vertices": len(V), "triangles": len(F), "iterations": ours["iterations"],
            "ours": {"lscm_ms": ours["lscm_ms"], "total_ms": ours["total_ms"], "distortion": dv},
            "libigl_arap": {"lscm_ms": igl_r["lscm_ms"], "arap_ms": igl_r["arap_ms"], "total_ms": igl_r["total_ms"],
                            "distortion": da},
            "libigl_lscm": {"ms": igl_r["lscm_ms"], "distortion": dl},
        })
    print("ours/igl: grade3d total time over libigl LSCM + ARAP (same iterations, same pins); on the LSCM row, LSCM "
          "times. grade3d holds boundary edges at their 3D length (seams), libigl's ARAP does not.")
    if args.json_out:
        with open(args.json_out, "w", encoding="utf-8") as f:
            json.dump(results, f, indent=1)


if __name__ == "__main__":
    main()
