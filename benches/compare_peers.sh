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
export PEERS_QUIET_WAIT=${PEERS_QUIET_WAIT:-30}

cargo build --release --quiet
BIN=$PWD/target/release/cloth

if [[ -x $PEERS_VENV/bin/python ]]; then
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
    rates=()
    for _ in $(seq "$RUNS"); do
      rates+=("$("$BIN" run --scene "$scene" --set width="$n" --set height="$n" \
                 --steps 960 --warmup 16 --json |
               python3 -c 'import json,sys; print(json.load(sys.stdin)["steps_per_second"])')")
    done
    python3 - "$n" "$scene" "${rates[@]}" >> "$OUT/ours.jsonl" <<'PY'
import json, statistics, sys
n, scene, rates = int(sys.argv[1]), sys.argv[2], [float(r) for r in sys.argv[3:]]
print(json.dumps(dict(peer="cloth-sandbox (grid-f32, 2 threads)", N=n, wind=scene == "bench-wind",
                      steps_per_s=statistics.median(rates), runs=rates)))
PY
    echo "cloth-sandbox $scene N=$n: median $(tail -1 "$OUT/ours.jsonl" | python3 -c 'import json,sys; print(round(json.load(sys.stdin)["steps_per_s"]))') steps/s"
  done
done

python3 - "$OUT" <<'PY'
import json, os, sys
out = sys.argv[1]
rows = {}
for name in ("peers.jsonl", "ours.jsonl"):
    path = os.path.join(out, name)
    if not os.path.exists(path):
        continue
    for line in open(path):
        r = json.loads(line)
        rows.setdefault((r["wind"], r["peer"]), {})[r["N"]] = r["steps_per_s"]
sizes = sorted({n for cols in rows.values() for n in cols})
for wind in (False, True):
    print(f"\n{'with' if wind else 'without'} wind, steps/s (median of runs; 960 steps after 16 warm-up)\n")
    print("| simulator | " + " | ".join(f"N={n}" for n in sizes) + " |")
    print("|---|" + "---:|" * len(sizes))
    best = {}
    for (w, peer), cols in sorted(rows.items()):
        if w != wind:
            continue
        print(f"| {peer} | " + " | ".join(f"{cols[n]:,.0f}" if n in cols else "–" for n in sizes) + " |")
        if not peer.startswith("cloth-sandbox"):
            for n, v in cols.items():
                best[n] = max(best.get(n, 0), v)
    ours = next((c for (w, p), c in rows.items() if w == wind and p.startswith("cloth-sandbox")), {})
    if best:
        print("| ours / fastest peer | " + " | ".join(f"{ours[n] / best[n]:.1f}x" if n in ours and n in best else "–" for n in sizes) + " |")
print(f"\nraw results in {out}")
PY
