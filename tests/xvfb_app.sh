#!/usr/bin/env bash
# Drives the real app under Xvfb: start it, click a particle (pin), drag
# another, resize the window, press R, F1 twice (help), Ctrl+S (save), F12
# (screenshot), Ctrl+Z and Ctrl+Shift+Z (undo, redo), Tab twice (panel), Ctrl +
# drag (cut) and Ctrl+Z, G twice (reference), Esc, then Shift + drag a
# collider in the slide scene; passes when the app
# logged each action, exited 0 and its log holds no error or panic.
#
# Needs: Xvfb, xdotool (and ImageMagick's `import` when SHOT_DIR is set, to save
# screenshots there), a Vulkan or GL driver (Mesa's lavapipe will do).
# Usage: tests/xvfb_app.sh            (from the repository root)
#        CLOTH_BIN=path/to/cloth SHOT_DIR=/tmp/shots tests/xvfb_app.sh
set -euo pipefail

cd "$(dirname "$0")/.."
BIN=${CLOTH_BIN:-target/release/cloth}
if [[ ! -x $BIN ]]; then
    cargo build --release --quiet
fi
BIN=$(realpath "$BIN")
for tool in Xvfb xdotool; do
    command -v "$tool" >/dev/null || { echo "xvfb_app: $tool is not installed" >&2; exit 1; }
done

WORK=$(mktemp -d)
LOG=$WORK/app.log
XVFB_PID=""
APP_PID=""
cleanup() {
    [[ -n $APP_PID ]] && kill "$APP_PID" 2>/dev/null || true
    [[ -n $XVFB_PID ]] && kill "$XVFB_PID" 2>/dev/null || true
    rm -rf "$WORK"
}
trap cleanup EXIT
fail() {
    echo "xvfb_app: FAIL: $*" >&2
    echo "---- app log ----" >&2
    cat "$LOG" >&2 || true
    exit 1
}

# A free display, chosen by Xvfb itself.
Xvfb -displayfd 3 -screen 0 1280x800x24 -nolisten tcp 3>"$WORK/display" 2>"$WORK/xvfb.log" &
XVFB_PID=$!
for _ in $(seq 50); do [[ -s $WORK/display ]] && break; sleep 0.1; done
[[ -s $WORK/display ]] || fail "Xvfb did not start: $(cat "$WORK/xvfb.log")"
export DISPLAY=":$(head -1 "$WORK/display")"
export XDG_RUNTIME_DIR=$WORK/xdg
mkdir -m 700 "$XDG_RUNTIME_DIR"

# In a scratch working directory: Ctrl+S saves there.
mkdir "$WORK/cwd"
(cd "$WORK/cwd" && RUST_LOG=${RUST_LOG:-warn,cloth=info} exec "$BIN") >"$LOG" 2>&1 &
APP_PID=$!
WID=$(timeout 30 xdotool search --sync --name "cloth-sandbox" | head -1) || true
[[ -n $WID ]] || fail "no window titled cloth-sandbox appeared"
sleep 3
shot() { [[ -n ${SHOT_DIR:-} ]] && mkdir -p "$SHOT_DIR" && import -window root "$SHOT_DIR/$1.png" || true; }
# Esc quits; the app must exit 0 with a clean log: no ERROR-level line, panic,
# wgpu validation error or error message. (Mesa's XDG_RUNTIME_DIR notice and
# winit's WARN-level notes about Xvfb's missing XSETTINGS are not errors.)
quit_cleanly() {
    xdotool windowfocus --sync "$WID"
    xdotool key Escape
    set +e
    timeout 20 tail --pid="$APP_PID" -f /dev/null
    wait "$APP_PID"
    local status=$?
    set -e
    APP_PID=""
    [[ $status -eq 0 ]] || fail "$1: the app exited with status $status"
    if grep -E "^\[[^]]* ERROR |panicked|Validation Error|^error" "$LOG" | grep -q .; then
        fail "$1: the log has errors"
    fi
}
shot 1-default

# The window sits at (0, 0) (no window manager); the panel takes the left
# ~300 px and the cloth is framed in the middle of the rest, particles ~15 px apart.
# Pin: a click in the cloth's middle lands within the pick radius of a particle.
xdotool mousemove --window "$WID" 760 420 click 1
sleep 1
grep -q "pinned particle" "$LOG" || fail "clicking the cloth pinned no particle"
shot 2-pinned

# Drag: press on the cloth, move in steps, release.
xdotool mousemove --window "$WID" 700 560 mousedown 1
for step in 1 2 3 4 5 6 7 8; do
    xdotool mousemove --window "$WID" $((700 + step * 20)) $((560 + step * 8))
    sleep 0.1
done
sleep 0.5
shot 3-dragging
xdotool mouseup 1
sleep 0.5
grep -q "dragging particle" "$LOG" || fail "press-and-drag on the cloth grabbed no particle"
grep -q "released particle" "$LOG" || fail "releasing the mouse did not release the particle"

# Resize small and back (the scene keeps drawing beside the panel).
xdotool windowsize --sync "$WID" 420 260 || xdotool windowsize "$WID" 420 260
sleep 1
shot 4-small
xdotool windowsize --sync "$WID" 1200 760 || xdotool windowsize "$WID" 1200 760
sleep 1

# R resets, Esc quits (keys need focus first).
xdotool windowfocus --sync "$WID"
xdotool key r
sleep 1
grep -q "scene reset" "$LOG" || fail "R did not reset the scene"

# G compares with a reference (a ghost wireframe and the error), G again stops.
xdotool windowfocus --sync "$WID"
xdotool key g
sleep 3
shot 4b-reference
xdotool windowfocus --sync "$WID"
xdotool key g
sleep 1
grep -q "reference on" "$LOG" || fail "G did not turn the reference on"
grep -q "reference off" "$LOG" || fail "G again did not turn the reference off"
shot 5-reset

# F1 shows the help overlay and hides it again.
xdotool windowfocus --sync "$WID"
xdotool key F1
sleep 1
grep -q "help shown" "$LOG" || fail "F1 did not show the help"
shot 6-help
xdotool windowfocus --sync "$WID"
xdotool key F1
sleep 0.5
grep -q "help hidden" "$LOG" || fail "F1 again did not hide the help"

# Ctrl+S saves the setup in the working directory, as a scene file.
xdotool windowfocus --sync "$WID"
xdotool key ctrl+s
sleep 1
grep -q "saved the setup to" "$LOG" || fail "Ctrl+S did not save"
[[ -s $WORK/cwd/saved-cloth-1.toml ]] || fail "Ctrl+S wrote no saved-cloth-1.toml"
grep -q '^layout = "grid"' "$WORK/cwd/saved-cloth-1.toml" || fail "the saved file is no scene"

# F12 saves the view as a PNG in the working directory.
xdotool windowfocus --sync "$WID"
xdotool key F12
sleep 1
grep -q "saved a screenshot to" "$LOG" || fail "F12 saved no screenshot"
[[ $(head -c 8 "$WORK/cwd/screenshot-1.png" | od -An -tx1 | tr -d ' \n') == 89504e470d0a1a0a ]] ||
    fail "F12 wrote no PNG screenshot-1.png"

# Ctrl+Z takes back the last change (the pin clicked above); Ctrl+Shift+Z redoes it.
xdotool windowfocus --sync "$WID"
xdotool key ctrl+z
sleep 0.5
grep -q "Undo done" "$LOG" || fail "Ctrl+Z undid nothing"
xdotool windowfocus --sync "$WID"
xdotool key ctrl+shift+z
sleep 0.5
grep -q "Redo done" "$LOG" || fail "Ctrl+Shift+Z redid nothing"

# Tab hides the panel and shows it again.
xdotool windowfocus --sync "$WID"
xdotool key Tab
sleep 1
grep -q "panel hidden" "$LOG" || fail "Tab did not hide the panel"
shot 8-panel-hidden
xdotool key Tab
sleep 0.5
grep -q "panel shown" "$LOG" || fail "Tab again did not show the panel"

# Ctrl + drag across the cloth cuts it; Ctrl+Z mends the cut.
xdotool mousemove --window "$WID" 600 470
xdotool keydown ctrl
sleep 0.2
xdotool mousedown 1
for step in 1 2 3 4 5 6 7 8 9 10; do
    xdotool mousemove --window "$WID" $((600 + step * 30)) 470
    sleep 0.1
done
xdotool mouseup 1
sleep 0.2
xdotool keyup ctrl
sleep 0.5
shot 9-cut
grep -q "cut [0-9]* springs" "$LOG" || fail "Ctrl + drag across the cloth cut nothing"
xdotool windowfocus --sync "$WID"
xdotool key ctrl+z
sleep 0.5
[[ $(grep -c "Undo done" "$LOG") -ge 2 ]] || fail "Ctrl+Z after the cut undid nothing"

quit_cleanly "the default scene"
# The slide scene: Shift + drag on its box (framed in the middle of the view)
# moves it, and letting go keeps it where it was left.
LOG=$WORK/slide.log
(cd "$WORK/cwd" && RUST_LOG=${RUST_LOG:-warn,cloth=info} exec "$BIN" --scene slide) >"$LOG" 2>&1 &
APP_PID=$!
sleep 1
WID=$(timeout 30 xdotool search --sync --name "cloth-sandbox" | head -1) || true
[[ -n $WID ]] || fail "no window for the slide scene"
sleep 3
xdotool windowfocus --sync "$WID"
xdotool mousemove --window "$WID" 840 450
sleep 0.3
xdotool keydown shift
sleep 0.3
xdotool mousedown 1
for step in 1 2 3 4 5 6; do
    xdotool mousemove --window "$WID" $((840 - step * 30)) 440
    sleep 0.15
done
sleep 0.5
shot 7-collider-moved
xdotool mouseup 1
sleep 0.3
xdotool keyup shift
sleep 0.5
grep -q "moving collider 0 (box)" "$LOG" || fail "Shift + drag on the box took no collider"
grep -q "released collider 0" "$LOG" || fail "letting go did not release the collider"
quit_cleanly "the slide scene"
echo "xvfb_app: ok (pin, drag, resize, reset, help, save, screenshot, undo, redo, Tab, cut and undo, quit, Shift + drag a collider; exit 0, clean logs)"
