#!/usr/bin/env bash
# Instructions per particle-step of each kind of scene (benches/scene_cases.sh)
# against the plain `bench` cloth, counted by valgrind: the same count on every run,
# where the timed ratios of engine_scenes.sh move by a third on a shared machine.
# Each case runs twice under `valgrind --tool=callgrind` (100 and 300 steps, no
# warm-up, one thread); the difference is the cost of 200 steps, without the
# scene's setup. Usage: bash benches/instructions.sh [SIZES]   (default "128";
# a case at 128 x 128 takes about a minute; the 32^3 jelly against the bench
# closes the run).
#
# What it measures and what it does not. Valgrind's CPU has AVX2 and no AVX-512,
# so the kernels run their AVX2 build whatever the machine has: these are the AVX2
# path's ratios. Instructions are not time: a spill to the stack and a square
# root count one each. For the hot loops, which are bound by their vector
# arithmetic, the count of vector operations is the closer measure; the script
# prints both, the second over the whole run (packed arithmetic, compares,
# shuffles and conversions; not moves, broadcasts, or scalar `ss`/`sd`
# instructions, which the self-collision pass is made of).
set -euo pipefail
cd "$(dirname "$0")/.."
SIZES=${1:-"128"}
command -v valgrind > /dev/null || { echo "valgrind is not installed (apt-get install valgrind)"; exit 1; }
# CLOTH=path runs another build of the binary (e.g. a copy of an older commit's).
if [[ -z ${CLOTH:-} ]]; then
  cargo build --release --quiet
  CLOTH=target/release/cloth
fi
source benches/scene_cases.sh

# Instructions and vector operations of `cloth run ARGS --steps $1`, one thread.
count() {
  local steps=$1 out
  shift
  out=$(mktemp)
  eval "RAYON_NUM_THREADS=1 valgrind --tool=callgrind --dump-instr=yes --compress-pos=no \
    --compress-strings=no --callgrind-out-file=$out $CLOTH run $* --steps $steps --warmup 0" \
    > /dev/null 2>&1
  python3 - "$out" "$CLOTH" << 'PY'
import subprocess, sys
calls, binary = sys.argv[1], sys.argv[2]
total = vector = 0
costs = {}
obj, after_call = "", False
for line in open(calls):
    # The line after `calls=` gives the call's inclusive cost: not counted again.
    if line.startswith("calls="):
        after_call = True
    elif after_call:
        after_call = False
    elif line.startswith("ob="):
        obj = line[3:].strip()
    elif line.startswith("0x"):
        address, _, cost = line.split()[:3]
        total += int(cost)
        if obj.endswith("/" + binary.rsplit("/", 1)[-1]):
            costs[int(address, 16)] = costs.get(int(address, 16), 0) + int(cost)
names = {}
lo, hi = min(costs), max(costs) + 16
dump = subprocess.run(["objdump", "-d", "--no-show-raw-insn", f"--start-address={lo}",
                       f"--stop-address={hi}", binary], capture_output=True, text=True).stdout
for line in dump.splitlines():
    address, _, text = line.strip().partition(":")
    try:
        names[int(address, 16)] = text.split()[0] if text.split() else ""
    except ValueError:
        pass
skip = ("vmov", "vbroadcast", "vpbroadcast", "vinsert", "vextract", "vzero", "vpextr", "vpinsr")
for address, cost in costs.items():
    name = names.get(address, "")
    # Packed arithmetic, shuffles and conversions (not the scalar `ss`/`sd` ones).
    packed = name.endswith(("ps", "pd")) or name.startswith(("vp", "vperm"))
    if name.startswith("v") and packed and not name.startswith(skip):
        vector += cost
print(total, vector)
PY
  rm -f "$out"
}

# Instructions and vector operations per unit of work of `cloth run $1`: the counts
# of 300 steps less those of 100, over 200 steps of $2 units (particles or springs).
per_unit() {
  local first second
  first=$(count 100 "$1")
  second=$(count 300 "$1")
  python3 -c "
a, b = [list(map(int, s.split())) for s in ('$first', '$second')]
print(*((y - x) / (200 * $2) for x, y in zip(a, b)))"
}

echo "valgrind $(valgrind --version | sed 's/valgrind-//'): the AVX2 path; instructions per particle-step over steps 100 to 300"
for n in $SIZES; do
  echo
  echo "N = $n"
  printf '%-38s %14s %10s %14s %10s\n' "case" "instructions" "/bench" "vector ops" "/bench"
  base_all="" base_vec=""
  for c in "${!CASES[@]}"; do
    args="--set width=$n --set height=$n $(case_args "$c" "$n")"
    read -r all vec <<< "$(per_unit "$args" $((n * n)))"
    base_all=${base_all:-$all} base_vec=${base_vec:-$vec}
    python3 -c "print('%-38s %14.1f %10.2f %14.1f %10.2f' % ('${CASES[$c]%%|*}', $all, $all / $base_all, $vec, $vec / $base_vec))"
  done
done

# The jelly cube made 32^3 against the 128 x 128 bench, per spring-step (the lattice
# kernel's target is at most 2x; engine_scenes.sh times the same).
echo
JELLY="--scene jelly --set width=32 --set height=32 --set depth=32 --set origin=0,30,0"
BENCH="--scene bench --set width=128 --set height=128"
per_spring=()
for args in "$JELLY" "$BENCH"; do
  springs=$($CLOTH run $args --steps 1 --json | python3 -c "import json, sys; print(json.load(sys.stdin)['springs'])")
  per_spring+=("$(per_unit "$args" "$springs")")
done
python3 -c "
(ja, jv), (ba, bv) = [map(float, s.split()) for s in ('${per_spring[0]}', '${per_spring[1]}')]
print(f'jelly 32^3 per spring-step: {ja:.1f} instructions, {jv:.1f} vector ops; bench 128: {ba:.1f}, {bv:.1f}; cost {ja / ba:.2f}x and {jv / bv:.2f}x')"
