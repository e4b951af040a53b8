#!/usr/bin/env bash
# This build's speed against another build of `cloth` (an older commit's), in one
# run: the plain bench at 128, 256 and 512, then every built-in scene with 100
# particles or more, the grid scenes at 128 x 128 and the rest at their defaults.
# The two builds alternate, case by case, ROUNDS times; each keeps its best
# particle-steps/s (`cloth run --json`, STEPS steps after 16 warm-up steps).
# Usage: bash benches/against.sh OTHER_CLOTH [ROUNDS] [STEPS], e.g.
#   git worktree add /tmp/base a3d05af && (cd /tmp/base && cargo build --release)
#   bash benches/against.sh /tmp/base/target/release/cloth 5 960
set -euo pipefail
cd "$(dirname "$0")/.."
OTHER=${1:?usage: bash benches/against.sh OTHER_CLOTH [ROUNDS] [STEPS]}
ROUNDS=${2:-3}
STEPS=${3:-960}
cargo build --release --quiet
THIS=target/release/cloth

simd=$(grep -qw avx512f /proc/cpuinfo && echo AVX-512 || (grep -qw avx2 /proc/cpuinfo && echo AVX2 || echo baseline))
echo "SIMD level: $simd; $(nproc) cores; best of $ROUNDS rounds of $STEPS steps; ratio = this / other"

CASES=("bench 128|--scene bench --set width=128 --set height=128"
  "bench 256|--scene bench --set width=256 --set height=256"
  "bench 512|--scene bench --set width=512 --set height=512")
for scene in bars bench-wind cloth corners drape flag fold hanging sheet slide tear twist; do
  CASES+=("$scene 128|--scene $scene --set width=128 --set height=128")
done
for scene in jelly tablecloth table; do
  CASES+=("$scene|--scene $scene")
done

# The best rate of `$1 run $2`, or 0 when the run fails.
best_of() {
  local best=0 out rate
  out=$(eval "$1 run $2 --steps $STEPS --warmup 16 --json" 2>/dev/null | tail -1) || true
  rate=$(python3 -c "import json,sys; print(json.loads(sys.argv[1])['particle_steps_per_second'])" "$out" 2>/dev/null || echo 0)
  echo "$rate"
}

printf '%-16s %14s %14s %8s\n' "case" "this M p-s/s" "other M p-s/s" "ratio"
for c in "${CASES[@]}"; do
  name=${c%%|*}
  args=${c#*|}
  this=0
  other=0
  for _ in $(seq "$ROUNDS"); do
    this=$(python3 -c "print(max($this, $(best_of "$THIS" "$args")))")
    other=$(python3 -c "print(max($other, $(best_of "$OTHER" "$args")))")
  done
  python3 -c "
t, o = $this, $other
print(f'%-16s %14.2f %14.2f %8s' % ('$name', t / 1e6, o / 1e6, f'{t / o:.2f}' if o > 0 else 'n/a'))"
done
