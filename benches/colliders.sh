#!/usr/bin/env bash
# The colliders' cost against the drape (one sphere) at 128 x 128, in one run:
# `cloth run --json`, best of RUNS runs of STEPS steps, while the cloth falls (after
# 16 warm-up steps) and once it has settled over the colliders (after 2 s), for
#   - drape: the drape scene at 128 x 128, its sphere the scene's `sphere_center`;
#   - far: the drape with one more sphere collider far off, that nothing touches:
#     what running on an engine that has colliders costs, without their work;
#   - three: the same cloth over three analytic colliders (a sphere, a box and a
#     capsule, `[[colliders]]`);
#   - mesh20k: the same cloth over a 20,480-triangle sphere mesh collider (twice the 10,000 asked for).
# Usage: bash benches/colliders.sh [RUNS] [STEPS]
set -euo pipefail
cd "$(dirname "$0")/.."
RUNS=${1:-3}
STEPS=${2:-960}
cargo build --release --quiet
BIN=$PWD/target/release/cloth
DIR=$(mktemp -d)
trap 'rm -rf "$DIR"' EXIT
python3 benches/colliders/make_sphere_mesh.py 5 > "$DIR/sphere20k.obj"
# The drape's cloth at 128 x 128 over the same 1.95 m, without self-collision (the
# same in all three, and not what is measured).
BASE='--set width=128 --set height=128 --set rest_length=0.01535 --set self_collision=false --set thickness=0.012'
for case in drape far three mesh20k; do
  scene=assets/scenes/drape.toml
  if [[ $case != drape ]]; then
    scene=$DIR/$case.toml
    grep -v '^sphere_' assets/scenes/drape.toml > "$scene"
    cat "benches/colliders/$case.toml" >> "$scene"
    sed -i "s|@MESH@|$DIR/sphere20k.obj|" "$scene"
  fi
  line="$case"
  for warmup in 16 1920; do
    best=0
    for _ in $(seq "$RUNS"); do
      # shellcheck disable=SC2086
      rate=$("$BIN" run --scene "$scene" $BASE --steps "$STEPS" --warmup "$warmup" --json |
        python3 -c 'import json,sys; d=json.load(sys.stdin); print(d["steps_per_second"], d["engine"])')
      best=$(python3 -c "import sys; a,b=sys.argv[1],sys.argv[2].split()[0]; print(max(float(a), float(b)))" "$best" "$rate")
      engine=${rate#* }
    done
    line="$line $best"
  done
  echo "$line $engine"
done | python3 -c '
import sys
rows = [l.split() for l in sys.stdin]
fall, settled = float(rows[0][1]), float(rows[0][2])
print("%-10s %10s %6s %10s %6s  engine" % ("case", "falling", "cost", "settled", "cost"))
for name, a, b, engine in rows:
    a, b = float(a), float(b)
    print(f"{name:10} {a:10.0f} {fall / a:5.2f}x {b:10.0f} {settled / b:5.2f}x  {engine}")
'
