#!/usr/bin/env bash
# Times the peers' benchmark cloth (shared/peers: Newton, hand-written Warp, Taichi)
# and `cloth run` on the same scene, one after the other on this machine, and prints
# one table of steps/s (median of RUNS runs of 960 steps after 16 untimed warm-up
# steps, as the peers' harness does).
#
#   bash benches/compare_peers.sh            # sizes 32,64,128,256 (+512 for ours)
#   PEERS_VENV=/path/to/venv RUNS=5 SIZES=128,256 bash benches/compare_peers.sh
#
# Needs the peers' Python environment (shared/peers/README.md, section 5:
# `pip install warp-lang newton taichi` in a venv); without it, only ours is timed.
set -euo pipefail
cd "$(dirname "$0")/.."
PEERS_DIR=${PEERS_DIR:-../shared/peers}
PEERS_VENV=${PEERS_VENV:-/tmp/peers-venv}
SIZES=${SIZES:-32,64,128,256}
RUNS=${RUNS:-5}
OUT=${OUT:-$(mktemp -d)}
mkdir -p "$OUT"
export PEERS_QUIET_WAIT=${PEERS_QUIET_WAIT:-30}

cargo build --release --quiet
BIN=$PWD/target/release/cloth

if [[ -n ${REUSE_PEERS:-} ]]; then
  cp "$REUSE_PEERS" "$OUT/peers.jsonl"   # peer results from an earlier run of this script
elif [[ -x $PEERS_VENV/bin/python ]]; then
  for wind in "" "--wind"; do
    (cd "$PEERS_DIR" && for cmd in "newton_bench.py --graph" "warp_bench.py --graph" \
                                   "taichi_bench.py --style gather --threads 2"; do
       # shellcheck disable=SC2086
       "$PEERS_VENV/bin/python" $cmd $wind --sizes "$SIZES" --runs "$RUNS" \
         --out "$OUT/peers.jsonl" 2>&1 | grep --line-buffered -E "steps/s" || true
     done)
  done
else
  echo "no peer environment at $PEERS_VENV: timing cloth-sandbox only" >&2
fi

for n in ${SIZES//,/ } 512; do
  for scene in bench bench-wind; do
    runs=()
    for _ in $(seq "$RUNS"); do
      # Exit 3 (diverged) still prints the JSON, with the steps that ran.
      runs+=("$("$BIN" run --scene "$scene" --set width="$n" --set height="$n" \
                 --steps 960 --warmup 16 --json || true)")
    done
    python3 - "$n" "$scene" "${runs[@]}" >> "$OUT/ours.jsonl" <<'PY'
import json, statistics, sys
n, scene = int(sys.argv[1]), sys.argv[2]
runs = [json.loads(r) for r in sys.argv[3:]]
rates = [r["steps_per_second"] for r in runs]
diverged = next((r["diverged"]["time"] for r in runs if "diverged" in r), None)
print(json.dumps(dict(peer="cloth-sandbox (grid-f32, 2 threads)", N=n, wind=scene == "bench-wind",
                      steps_per_s=statistics.median(rates), runs=rates, diverged_at=diverged)))
PY
    echo "cloth-sandbox $scene N=$n: median $(tail -1 "$OUT/ours.jsonl" | python3 -c 'import json,sys; print(round(json.load(sys.stdin)["steps_per_s"]))') steps/s"
  done
done

python3 - "$OUT" <<'PY'
import json, os, sys
out = sys.argv[1]
rows, notes, marked = {}, [], set()
for name in ("peers.jsonl", "ours.jsonl"):
    path = os.path.join(out, name)
    if not os.path.exists(path):
        continue
    for line in open(path):
        r = json.loads(line)
        rows.setdefault((r["wind"], r["peer"]), {})[r["N"]] = r["steps_per_s"]
        if r.get("diverged_at") is not None:
            notes.append(f"{r['peer']}, N={r['N']}, {'with' if r['wind'] else 'without'} wind: "
                         f"the cloth diverged at t = {r['diverged_at']:.2f} s; steps/s is over the steps before it")
            marked.add((r["wind"], r["peer"], r["N"]))
sizes = sorted({n for cols in rows.values() for n in cols})
for wind in (False, True):
    print(f"\n{'with' if wind else 'without'} wind, steps/s (median of runs; 960 steps after 16 warm-up)\n")
    print("| simulator | " + " | ".join(f"N={n}" for n in sizes) + " |")
    print("|---|" + "---:|" * len(sizes))
    best = {}
    for (w, peer), cols in sorted(rows.items()):
        if w != wind:
            continue
        cell = lambda n: f"{cols[n]:,.0f}" + (" †" if (w, peer, n) in marked else "") if n in cols else "–"
        print(f"| {peer} | " + " | ".join(cell(n) for n in sizes) + " |")
        if not peer.startswith("cloth-sandbox"):
            for n, v in cols.items():
                best[n] = max(best.get(n, 0), v)
    ours = next((c for (w, p), c in rows.items() if w == wind and p.startswith("cloth-sandbox")), {})
    if best:
        print("| ours / fastest peer | " + " | ".join(f"{ours[n] / best[n]:.1f}x" if n in ours and n in best else "–" for n in sizes) + " |")
for note in notes:
    print(f"\n† {note}")
print(f"\nraw results in {out}")
PY
