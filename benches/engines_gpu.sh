#!/usr/bin/env bash
# The plain cloth (the peers' bench) on the CPU and the GPU engine, in one run:
# `cloth run --engine cpu|gpu --json` at N x N for N in SIZES, STEPS steps after
# 16 warm-up steps (16 substeps of a 1/60 s frame by default), printing steps/s,
# particle-steps/s and the GPU's rate as a multiple of the CPU's. On a CPU
# adapter (lavapipe) the GPU figures are the adapter's, not a GPU's.
# Usage: bash benches/engines_gpu.sh [STEPS] [SIZES...]   (default 16; 256 512 1024 2048)
set -euo pipefail
cd "$(dirname "$0")/.."
STEPS=${1:-16}
shift || true
SIZES=${*:-256 512 1024 2048}
cargo build --release --quiet
BIN=$PWD/target/release/cloth
# steps/s, engine and adapter (or SIMD level); a refused run prints `nan refused`
# and its message on stderr.
rate() {
  local out
  if out=$("$BIN" run --scene bench --set width="$1" --set height="$1" --steps "$STEPS" \
      --warmup 16 --engine "$2" --json 2>"$ERR"); then
    python3 -c 'import json,sys; d=json.load(sys.stdin); print(d["steps_per_second"], d["engine"], d["adapter"] or d["simd"])' <<<"$out"
  else
    echo "$1 x $1 on $2: $(grep -v XDG_RUNTIME "$ERR")" >&2
    echo "nan refused -"
  fi
}
ERR=$(mktemp)
trap 'rm -f "$ERR"' EXIT
printf '%6s  %12s %14s  %12s %14s  %8s  %s\n' N cpu_steps/s cpu_pstep/s gpu_steps/s gpu_pstep/s gpu/cpu adapter
for n in $SIZES; do
  read -r cpu cpu_engine cpu_simd < <(rate "$n" cpu)
  read -r gpu _ adapter < <(rate "$n" gpu)
  python3 - "$n" "$cpu" "$gpu" "$cpu_engine $cpu_simd" "$adapter" <<'PY'
import sys
n, cpu, gpu = int(sys.argv[1]), float(sys.argv[2]), float(sys.argv[3])
p = n * n
ratio = gpu / cpu if cpu == cpu and gpu == gpu else float("nan")
print(f"{n:6d}  {cpu:12.1f} {cpu*p:14.3e}  {gpu:12.1f} {gpu*p:14.3e}  {ratio:8.3f}  cpu {sys.argv[4]}; gpu {sys.argv[5]}")
PY
done
