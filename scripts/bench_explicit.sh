#!/usr/bin/env bash
# loam's explicit MPM against the Taichi peer, side by side in one sitting (docs/benchmarks.md,
# Explicit speed): the criterion bench of the 2D (256 x 256 cells) and 3D (32^3) elastic blocks,
# then, when taichi is installed (pip install taichi), the peer's MLS-MPM on the same blocks with
# as many threads, and the ratio of the medians. Usage: scripts/bench_explicit.sh [OUT_DIR]
set -euo pipefail
cd "$(dirname "$0")/.."
out=${1:-target/bench_explicit}
threads=${RAYON_NUM_THREADS:-$(nproc)}
mkdir -p "$out"
cargo bench -p loam-bench --bench explicit -- --warm-up-time 1 --measurement-time 5 | tee "$out/loam.txt"
if ! python3 -c "import taichi" 2>/dev/null; then
    echo "taichi is not installed (pip install taichi): no peer figures"
    exit 0
fi
python3 scripts/peers/taichi_mls_mpm_block.py 256 200 "$threads" | tee "$out/taichi.txt"
python3 scripts/peers/taichi_mls_mpm_block3d.py 32 50 "$threads" | tee -a "$out/taichi.txt"
python3 - "$out" <<'PY'
import re, sys, pathlib
out = pathlib.Path(sys.argv[1])
scale = {"elem/s": 1e-6, "Kelem/s": 1e-3, "Melem/s": 1.0, "Gelem/s": 1e3}
loam, name = {}, None
for line in (out / "loam.txt").read_text().splitlines():
    m = re.search(r"explicit/(\S+)", line)
    if m:
        name = m.group(1)
    m = re.search(r"thrpt:\s*\[([^\]]+)\]", line)
    if m and name and "%" not in m.group(1):
        v = m.group(1).split()
        loam[name] = float(v[2]) * scale[v[3]]  # the median: [low unit median unit high unit]
peer = {}
for line in (out / "taichi.txt").read_text().splitlines():
    m = re.search(r"([0-9.]+) M point-steps/s", line)
    if m:
        peer["3d" if " 3D " in line else "2d"] = float(m.group(1))
rows = ["| block | loam (M point-steps/s) | Taichi | loam / Taichi |", "|---|---:|---:|---:|"]
for name, v in sorted(loam.items()):
    dim = "3d" if "_3d_" in name else "2d"
    p = peer.get(dim) if name.startswith("block_") else None  # the peer's blocks, from rest
    rows.append(f"| {name} | {v:.2f} | {p:.2f} | {v / p:.2f} |" if p else f"| {name} | {v:.2f} | — | — |")
scaling = [v for name, v in loam.items() if name.startswith("scaling_2d_")]
if len(scaling) > 1:
    rows.append(f"\nscaling (2D GIMP, same state of motion): the slowest {100 * (1 - min(scaling) / max(scaling)):.1f} % below the fastest")
table = "\n".join(rows)
(out / "ratio.md").write_text(table + "\n")
print(table)
PY
