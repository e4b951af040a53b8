#!/usr/bin/env bash
# The app's frame time while idle and while the stiffness slider is dragged
# continuously (a live edit every frame), under Xvfb on this machine's renderer.
# Usage: [ROUNDS=R] bash benches/xvfb_slider_drag.sh [N] [SECONDS]
# (default: the 256x256 cloth, 8 s, one round). With ROUNDS, each round starts the
# app afresh, and the last line gives every round's frame while dragging against
# idle and their median: one round's 20 or so frames part by as much as the drag
# changes them.
set -euo pipefail
cd "$(dirname "$0")/.."
N=${1:-256}
SECS=${2:-8}
ROUNDS=${ROUNDS:-1}
cargo build --release --quiet
if [ "$ROUNDS" -gt 1 ]; then
  OUT=$(mktemp)
  trap 'rm -f "$OUT"' EXIT
  for r in $(seq "$ROUNDS"); do
    echo "round $r"
    ROUNDS=1 bash "$0" "$N" "$SECS" | tee -a "$OUT"
  done
  # "idle    : frame F ms" then "dragging: frame F ms", a pair a round.
  awk '/^idle/ {idle = $4} /^dragging/ {print 100 * ($3 / idle - 1)}' "$OUT" | sort -g |
    awk '{r[NR] = $1; s = s sprintf(" %+.1f%%", $1)}
      END {m = NR % 2 ? r[(NR + 1) / 2] : (r[NR / 2] + r[NR / 2 + 1]) / 2
        printf "frame while dragging against idle, %d rounds (sorted):%s; median %+.1f%%\n", NR, s, m}'
  exit 0
fi
WORK=$(mktemp -d)
Xvfb -displayfd 3 -screen 0 1280x800x24 -nolisten tcp 3>"$WORK/display" 2>/dev/null &
XVFB=$!
trap 'kill $APP $XVFB 2>/dev/null; rm -rf "$WORK"' EXIT
for _ in $(seq 50); do [[ -s $WORK/display ]] && break; sleep 0.1; done
export DISPLAY=":$(head -1 "$WORK/display")" XDG_RUNTIME_DIR=$WORK
chmod 700 "$WORK"
RUST_LOG=warn,cloth::frames=debug,cloth::app=debug target/release/cloth --scene cloth --set width="$N" --set height="$N" 2>"$WORK/log" &
APP=$!
WID=$(timeout 30 xdotool search --sync --name cloth-sandbox | head -1)
sleep 5
idle_from=$(wc -l <"$WORK/log")
sleep "$SECS"
idle_to=$(wc -l <"$WORK/log")
# The stiffness slider's handle (panel row at y = 481 in the 1200 x 760 window),
# moved back and forth by a few pixels (k within about 20% of its value, so the
# physics costs the same): a new stiffness every frame. The edits are counted
# from the app's log below, so a panel laid out anew fails loudly.
Y=481
# One xdotool for the whole drag: a process started for each of the 50 moves a
# second took the two cores from the app (the frame time rose by 7% with the
# moves outside the window, where the app sees none of them).
moves=()
x=80
for _ in $(seq $((SECS * 50))); do
  moves+=(mousemove --window "$WID" $x $Y sleep 0.02)
  x=$(( x >= 84 ? 80 : x + 1 ))
done
xdotool mousemove --window "$WID" 82 $Y mousedown 1
drag_from=$(wc -l <"$WORK/log")
xdotool "${moves[@]}"
drag_to=$(wc -l <"$WORK/log")
[ -n "${SHOT:-}" ] && import -window root "$SHOT"
xdotool mouseup 1
summary() {
  # "frame F ms, R frames/s, real-time factor X of Y asked, physics busy B%, S steps/s",
  # a line about every second. F is the panel's moving average over about ten
  # frames, seconds behind at these rates: the frame time here is from the frames
  # counted in each line's window, 1000 / (mean of R).
  sed -n "$(($1 + 1)),$2p" "$WORK/log" | grep -o 'frame [0-9.]* ms, .*steps/s' | tr -d ',%' |
    awk -v what="$3" '{r += $4; x += $8; b += $14; n++} END {if (n) printf "%s: frame %.1f ms (%.2f frames/s), real-time factor %.3f, physics busy %.0f%% (%d samples)\n", what, 1000 * n / r, r / n, x/n, b/n, n; else print what ": no samples"}'
}
summary "$idle_from" "$idle_to" "idle    "
summary "$drag_from" "$drag_to" "dragging"
edits=$(sed -n "$((drag_from + 1)),${drag_to}p" "$WORK/log" | grep -c 'edit Stiffness' || true)
echo "stiffness edits while dragging: $edits"
if [ "$edits" -eq 0 ]; then
  echo "the drag changed no stiffness: the slider is not at y = $Y (take a screenshot: SHOT=shot.png)" >&2
  exit 1
fi
