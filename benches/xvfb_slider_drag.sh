#!/usr/bin/env bash
# The app's frame time while idle and while the stiffness slider is dragged
# continuously (a live edit every frame), under Xvfb on this machine's renderer.
# Usage: bash benches/xvfb_slider_drag.sh [N] [SECONDS]   (default: the 256x256 cloth, 8 s)
set -euo pipefail
cd "$(dirname "$0")/.."
N=${1:-256}
SECS=${2:-8}
cargo build --release --quiet
WORK=$(mktemp -d)
Xvfb -displayfd 3 -screen 0 1280x800x24 -nolisten tcp 3>"$WORK/display" 2>/dev/null &
XVFB=$!
trap 'kill $APP $XVFB 2>/dev/null; rm -rf "$WORK"' EXIT
for _ in $(seq 50); do [[ -s $WORK/display ]] && break; sleep 0.1; done
export DISPLAY=":$(head -1 "$WORK/display")" XDG_RUNTIME_DIR=$WORK
chmod 700 "$WORK"
RUST_LOG=warn,cloth::frames=debug target/release/cloth --scene cloth --set width="$N" --set height="$N" 2>"$WORK/log" &
APP=$!
WID=$(timeout 30 xdotool search --sync --name cloth-sandbox | head -1)
sleep 5
idle_from=$(wc -l <"$WORK/log")
sleep "$SECS"
idle_to=$(wc -l <"$WORK/log")
# The stiffness slider's handle (panel row at y = 261), moved back and forth by a
# few pixels (k within about 20% of its value, so the physics costs the same): a
# new stiffness every frame.
xdotool mousemove --window "$WID" 82 261 mousedown 1
end=$((SECONDS + SECS))
drag_from=$(wc -l <"$WORK/log")
x=80
while [ $SECONDS -lt $end ]; do
  xdotool mousemove --window "$WID" $x 261
  x=$(( x >= 84 ? 80 : x + 1 ))
  sleep 0.02
done
drag_to=$(wc -l <"$WORK/log")
[ -n "${SHOT:-}" ] && import -window root "$SHOT"
xdotool mouseup 1
summary() {
  # "frame F ms, R frames/s, real-time factor X of Y asked, physics busy B%, S steps/s"
  sed -n "$(($1 + 1)),$2p" "$WORK/log" | grep -o 'frame [0-9.]* ms, .*steps/s' | tr -d ',%' |
    awk -v what="$3" '{f += $2; x += $8; b += $14; n++} END {if (n) printf "%s: frame %.1f ms, real-time factor %.3f, physics busy %.0f%% (%d samples)\n", what, f/n, x/n, b/n, n; else print what ": no samples"}'
}
summary "$idle_from" "$idle_to" "idle    "
summary "$drag_from" "$drag_to" "dragging"
