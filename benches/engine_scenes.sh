#!/usr/bin/env bash
# Cost per particle-step of each kind of scene on the fast engine against the plain
# `bench` cloth, in one run: `cloth run --json` (STEPS steps after 16 warm-up steps,
# best of RUNS runs), at each size. Usage: bash benches/engine_scenes.sh [SIZES] [RUNS] [STEPS]
# e.g. bash benches/engine_scenes.sh "128 256" 3 3840; RAYON_NUM_THREADS=1 before it
# runs every case on one core. Each ratio is given best against best, median against
# median, and paired: the median over the rounds of the bench's rate over the case's
# in the same round (each round runs every case once, one after another). On a noisy
# machine the three part, and say how far (one lucky bench run moves every case's
# best against best; the paired ratio compares runs seconds apart). Runs of 960 steps at 128 x 128
# last about 40 ms, and on a 2-core VM how soon the system spreads the two threads
# decides much of such a run; longer runs give steadier ratios.
set -euo pipefail
cd "$(dirname "$0")/.."
SIZES=${1:-"128 256"}
RUNS=${2:-3}
STEPS=${3:-960}
# SIMD=avx2 (or baseline) runs every case's loops at that level (`cloth run --simd`),
# e.g. the AVX2 path on an AVX-512 machine.
# CLOTH=path runs another build of the binary (e.g. a copy of an older commit's).
if [[ -z ${CLOTH:-} ]]; then
  cargo build --release --quiet
  CLOTH=target/release/cloth
fi

source benches/scene_cases.sh

simd=$(grep -qw avx512f /proc/cpuinfo && echo AVX-512 || (grep -qw avx2 /proc/cpuinfo && echo AVX2 || echo baseline))
SIMD_ARGS=""
if [[ -n ${SIMD:-} ]]; then
  simd="$SIMD (asked for; the CPU has $simd)"
  SIMD_ARGS="--simd $SIMD"
fi
echo "SIMD level: $simd; $(nproc) cores; best of $RUNS runs of $STEPS steps"
for n in $SIZES; do
  echo
  echo "N = $n"
  printf '%-38s %-12s %14s %10s %10s %10s\n' "case" "engine" "M p-steps/s" "cost/bench" "(medians)" "(paired)"
  # The runs go round the cases (case 1, 2, ..., then again), so that a spell of
  # contention on a shared machine slows one run of every case, not every run of
  # one: each case keeps all its runs, for the best and the median.
  declare -a args_of rates_of engine_of
  for c in "${!CASES[@]}"; do
    args_of[$c]=$(case_args "$c" "$n")
    rates_of[$c]=""
  done
  for _ in $(seq "$RUNS"); do
    for c in "${!CASES[@]}"; do
      # shellcheck disable=SC2086
      out=$(eval "$CLOTH run $SIMD_ARGS --set width=$n --set height=$n ${args_of[$c]} --steps $STEPS --warmup 16 --json" 2>/dev/null | tail -1) || true
      read -r rate engine < <(python3 -c "import json,sys; d=json.loads(sys.argv[1]); print(d['particle_steps_per_second'], d['engine'] + ('' if d['steps'] == $STEPS else '(diverged)'))" "$out")
      engine_of[$c]=$engine
      rates_of[$c]="${rates_of[$c]} $rate"
    done
  done
  for c in "${!CASES[@]}"; do
    read -r best ratio median_ratio paired < <(python3 -c "
import statistics, sys
base, rates = [list(map(float, a.split())) for a in sys.argv[1:]]
paired = statistics.median(b / r for b, r in zip(base, rates))
print(max(rates) / 1e6, max(base) / max(rates), statistics.median(base) / statistics.median(rates), paired)
" "${rates_of[0]}" "${rates_of[$c]}")
    printf '%-38s %-12s %14.1f %10.2f %10.2f %10.2f\n' "${CASES[$c]%%|*}" "${engine_of[$c]}" "$best" "$ratio" "$median_ratio" "$paired"
  done
done

# The jelly cube made 32^3 (lifted clear of the ground; in 1,024 steps of 0.2 ms it
# falls 0.2 m of its 30) against the 128 x 128 bench, per spring-step: the lattice
# kernel's target is at most 2x. 1,024 steps, with the engines' energy check among
# them as often as in a long run (every 1,024 steps, as the bench's); runs of 200
# steps lasted 50 ms, and their rate moved with whatever else the machine did then.
echo
JELLY="--scene jelly --set width=32 --set height=32 --set depth=32 --set origin=0,30,0 --steps 1024"
BENCH="--scene bench --set width=128 --set height=128 --steps $STEPS"
# RUNS rounds of a jelly run then a bench run (in turn, as above), each keeping
# its fastest.
for _ in $(seq "$RUNS"); do
  for args in "$JELLY" "$BENCH"; do
    # shellcheck disable=SC2086
    echo "$args|$($CLOTH run $SIMD_ARGS $args --warmup 16 --json 2>/dev/null | tail -1 || true)"
  done
done | python3 -c "
import json, sys
best = {}
for line in sys.stdin:
    args, _, out = line.partition('|')
    if out.startswith('{'):
        d = json.loads(out)
        if d['spring_steps_per_second'] > best.get(args, {}).get('spring_steps_per_second', 0):
            best[args] = d
j, b = best[sys.argv[1]], best[sys.argv[2]]
rj, rb = j['spring_steps_per_second'], b['spring_steps_per_second']
print(f\"jelly 32^3 on {j['engine']}: {rj:.3e} spring-steps/s; bench 128: {rb:.3e}; cost per spring-step {rb / rj:.2f}x\")
" "$JELLY" "$BENCH"
