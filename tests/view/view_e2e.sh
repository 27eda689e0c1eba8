#!/usr/bin/env bash
# vpm-view as a person uses it: a real X server (Xvfb), vpm-server on an
# ephemeral port with a token and the 128^3 phantom, vpm-view in a window,
# real mouse and key events through xdotool, and screenshots of the window
# (ImageMagick's import). Asserts that
#   - the first frame appears and is not blank (pixel statistics),
#   - an orbit drag changes the picture,
#   - the help overlay (h) shows and hides,
#   - a preset key (3) changes the picture,
#   - grab mode (g) + a left drag deforms the volume (the server's
#     max_displacement_mm in the frames vpm-view logs) and releasing lets go,
#   - a drag released with Shift is kept; Ctrl+Z takes it back and
#     Ctrl+Shift+Z brings it back (the server keeps cases: --state-dir),
#   - S saves a PNG screenshot,
#   - L shows three slices beside the 3D frame (2 x 2) and hides them; the
#     wheel over a slice scrolls it in equal steps, and grab mode on a slice
#     grabs and drags the tissue on its plane,
#   - B (crop box): dragging the face under the cursor moves it and changes
#     the frame; C (clip plane) cuts the front away and PageUp moves it 1 mm;
#     P adds a second plane after an orbit and PageUp moves only that one,
#   - resizing the window brings frames of the new size,
#   - killing the server shows a red "connection lost" banner, and a server
#     restarted on the same port (and state directory) is reconnected to:
#     the viewer reopens its case and shows the same displacement,
#   - q quits with exit status 0.
#
# Usage: view_e2e.sh BUILD_DIR
set -uo pipefail
build=$(cd "${1:?usage: $0 BUILD_DIR}" && pwd)
server_bin="$build/server/service/vpm-server"
view_bin="$build/client/vpm-view"
for b in "$server_bin" "$view_bin"; do
  [ -x "$b" ] || { echo "FAIL: $b is not built"; exit 1; }
done
for tool in Xvfb xdotool import convert compare xdpyinfo; do
  command -v "$tool" >/dev/null || { echo "FAIL: $tool is not installed (scripts/install-deps.sh)"; exit 1; }
done

tmp=$(mktemp -d)
xvfb_pid="" server_pid="" view_pid=""
cleanup() {
  for pid in $view_pid $server_pid $xvfb_pid; do kill -TERM "$pid" 2>/dev/null; done
  sleep 0.5
  for pid in $view_pid $server_pid $xvfb_pid; do kill -KILL "$pid" 2>/dev/null; done
  if [ "${keep_tmp:-0}" = 1 ]; then echo "logs and screenshots kept in $tmp"; else rm -rf "$tmp"; fi
}
trap cleanup EXIT
failures=0
fail() { echo "FAIL: $* [${SECONDS} s]"; failures=$((failures + 1)); keep_tmp=1; }
pass() { echo "ok:   $* [${SECONDS} s]"; }
die() { echo "FAIL: $*"; keep_tmp=1; echo "--- vpm-view stderr"; cat "$tmp/view.err" 2>/dev/null;
        echo "--- server log"; cat "$tmp/server.log" 2>/dev/null; exit 1; }

# wait_for SECONDS COMMAND...: polls every 0.1 s until COMMAND succeeds.
wait_for() {
  local deadline=$((SECONDS + $1)); shift
  until "$@"; do
    [ $SECONDS -ge $deadline ] && return 1
    sleep 0.1
  done
}

# --- X server on a free display
display=""
for n in $(seq 90 199); do
  if [ ! -e "/tmp/.X$n-lock" ] && [ ! -e "/tmp/.X11-unix/X$n" ]; then display=":$n"; break; fi
done
[ -n "$display" ] || die "no free X display in :90..:199"
Xvfb "$display" -screen 0 800x600x24 -nolisten tcp > "$tmp/xvfb.log" 2>&1 &
xvfb_pid=$!
disown "$xvfb_pid"  # no "Killed" notice from bash when cleanup ends it
export DISPLAY="$display"
wait_for 10 xdpyinfo >/dev/null 2>&1 || die "Xvfb did not start on $display: $(cat "$tmp/xvfb.log")"

# --- server
token=$(head -c 12 /dev/urandom | od -An -tx1 | tr -d ' \n')
port=""
test_listening() { [ "$(grep -c "listening on port" "$tmp/server.log")" -gt "$1" ]; }
listening_or_gone() { test_listening "$1" || ! kill -0 "$server_pid" 2>/dev/null; }
# Starts vpm-server and waits until it listens. A server that exits at once
# (the port of a killed server not yet free, a binary being relinked in the
# shared build tree) is tried again, up to 5 times.
start_server() {  # LISTEN_ADDRESS
  local before attempt
  for attempt in 1 2 3 4 5; do
    touch "$tmp/server.log"
    before=$(grep -c "listening on port" "$tmp/server.log")
    "$server_bin" --listen "$1" --token "$token" --state-dir "$tmp/state" \
      >> "$tmp/server.log" 2>&1 &
    server_pid=$!
    wait_for 60 listening_or_gone "$before" || die "vpm-server did not listen within 60 s"
    if test_listening "$before"; then
      port=$(sed -n 's/^vpm-server listening on port \([0-9]*\).*/\1/p' "$tmp/server.log" | tail -1)
      return 0
    fi
    echo "note: vpm-server exited at start (attempt $attempt): $(tail -2 "$tmp/server.log")"
    sleep 1
  done
  die "vpm-server did not start"
}
start_server 127.0.0.1:0

# --- viewer
frame_w=256 frame_h=256
VPM_TOKEN="$token" "$view_bin" --server "127.0.0.1:$port" --volume "phantom:abdomen?size=128" \
  --size $frame_w $frame_h --log-frames --screenshot-dir "$tmp" > "$tmp/view.out" 2> "$tmp/view.err" &
view_pid=$!
window=$(timeout 30 xdotool search --sync --name '^vpm-view' | head -1)
[ -n "$window" ] || die "no vpm-view window appeared"
frames() { grep -c '^frame ' "$tmp/view.out"; }
more_frames_than() { [ "$(frames)" -gt "$1" ]; }
connects_at_least() { [ "$(grep -c 'vpm-view: connected' "$tmp/view.err")" -ge "$1" ]; }
# Frame log fields: frame N WxH seq S still|interactive max_displacement_mm D total_ms T rtt_ms R slices K
last_displacement() { awk '$1 == "frame" { d = $8 } END { print d + 0 }' "$tmp/view.out"; }
displaced_more_than() { gt "$(last_displacement)" "$1"; }
# Waits for frames after the first N and then for the stream to go quiet
# (the still frame that follows the last event).
settle() {  # N
  wait_for 60 more_frames_than "$1" || return 1
  local count=-1
  while [ "$(frames)" != "$count" ]; do count=$(frames); sleep 1.2; done
}
# NAME: the whole window as NAME-window.png and the frame area as NAME.png,
# less its bottom 24 rows, where short notices ("DVR ct-vessels") appear.
shot() {
  import -window "$window" "$tmp/$1-window.png" &&
    convert "$tmp/$1-window.png" -crop "${frame_w}x$((frame_h - 24))+0+0" +repage "$tmp/$1.png"
}
stddev() { convert "$1" -colorspace Gray -format '%[fx:standard_deviation]' info:; }
mean() { convert "$1" -colorspace Gray -format '%[fx:mean]' info:; }
# Normalised RMS difference of two images (0 equal, 1 opposite).
rmse() { compare -metric RMSE "$1" "$2" null: 2>&1 | sed -n 's/.*(\(.*\)).*/\1/p'; }
# Pixels whose colour differs by more than 5% between two images of one size.
changed_pixels() { compare -metric AE -fuzz 5% "$1" "$2" null: 2>&1 | sed 's/[^0-9].*//'; }
gt() { awk -v a="$1" -v b="$2" 'BEGIN { exit !(a > b) }'; }
# Rows of the window that are mostly banner red (the connection banner spans
# the window's width; red anatomy in a frame does not fill whole rows).
red_rows() {
  convert "$1" -scale '1x!' -fx '(r>0.5 && g<0.35 && b<0.35) ? 1 : 0' -format '%[fx:round(mean*h)]' info:
}
key() { xdotool windowfocus --sync "$window" 2>/dev/null; xdotool key --clearmodifiers "$@"; }
drag() {  # BUTTON X0 Y0 DX DY STEPS: press, move in steps, keep holding
  xdotool mousemove --window "$window" "$2" "$3" mousedown "$1"
  for i in $(seq 1 "$6"); do
    xdotool mousemove --window "$window" $(($2 + $4 * i / $6)) $(($3 + $5 * i / $6))
    sleep 0.08
  done
}

# 1. The first frame appears and is not blank.
wait_for 90 grep -q '^frame ' "$tmp/view.out" || die "no frame within 90 s"
settle 0
shot first || die "import could not capture the window"
sd=$(stddev "$tmp/first.png") m=$(mean "$tmp/first.png")
if gt "$sd" 0.05 && gt "$m" 0.03; then pass "first frame shown (mean $m, stddev $sd)"
else fail "first frame looks blank (mean $m, stddev $sd)"; fi

# 2. An orbit drag (left button) changes it.
n=$(frames)
drag 1 128 128 80 20 8; xdotool mouseup 1
settle "$n" || fail "no frame after the orbit drag"
shot orbit
d=$(rmse "$tmp/first.png" "$tmp/orbit.png")
if gt "$d" 0.02; then pass "orbit drag changed the picture (RMSE $d)"
else fail "orbit drag did not change the picture (RMSE $d)"; fi

# 3. Help overlay on and off.
key h; sleep 0.5; shot help
key h; sleep 0.5; shot nohelp
d_on=$(rmse "$tmp/orbit.png" "$tmp/help.png") d_off=$(rmse "$tmp/orbit.png" "$tmp/nohelp.png")
if gt "$d_on" 0.05 && ! gt "$d_off" 0.01; then pass "help overlay shows and hides (RMSE $d_on, $d_off)"
else fail "help overlay: RMSE with $d_on, after hiding $d_off"; fi

# 4. The vessel preset (3) shows inner structures that a pull visibly moves
# (the soft-tissue preset's skin hides most of the motion).
n=$(frames)
key 3
settle "$n" || fail "no frame after the preset key"
shot vessels
d=$(changed_pixels "$tmp/orbit.png" "$tmp/vessels.png")
if [ "$d" -gt 2000 ]; then pass "preset key 3 (ct-vessels) changed $d pixels"
else fail "preset key 3 changed only $d pixels"; fi

# 5. Grab mode, grab the centre, pull 40 px right and 30 px up, hold. The
# server refines the mesh at the grab (its default), which also brings the
# spine's fixed vertices near the centre into the mesh: the tissue there
# lags a long pull (the frame says by how much), so the bound is 8 mm.
key g
n=$(frames)
drag 1 128 128 40 -30 8
wait_for 60 displaced_more_than 8
settle "$n"
disp=$(last_displacement)
shot pulled
if gt "$disp" 8; then pass "grab and drag deformed the volume (server max_displacement_mm $disp)"
else fail "grab and drag: max_displacement_mm $disp (expected > 8 mm for a 50-pixel pull)"; fi
d=$(changed_pixels "$tmp/vessels.png" "$tmp/pulled.png")
if [ "$d" -gt 300 ]; then pass "the pull shows in the picture ($d pixels changed)"
else fail "the pull does not show in the picture (only $d pixels changed)"; fi
# The release's settle may take more than one frame, and a frame more than
# settle's quiet second under load: wait for the tissue to come back.
n=$(frames)
xdotool mouseup 1
released() { ! gt "$(last_displacement)" 0.001; }
wait_for 60 more_frames_than "$n" && wait_for 30 released
settle "$n"
disp=$(last_displacement)
if ! gt "$disp" 0.001; then pass "release let go (max_displacement_mm $disp)"
else fail "after release max_displacement_mm is $disp after 30 s"; fi
key g

# 5b. A drag released with Shift held is kept; Ctrl+Z takes it back (the
# whole grab, drag and release), Ctrl+Shift+Z brings it back.
key g
n=$(frames)
drag 1 128 128 40 -30 8
wait_for 60 displaced_more_than 8
# Shift down, button up, Shift up, while the viewer is stopped: it reads
# all three in one go (as under load), and the release must see Shift as
# of its own place among them, held.
kill -STOP "$view_pid"
xdotool keydown shift; sleep 0.1; xdotool mouseup 1; sleep 0.1; xdotool keyup shift; sleep 0.2
kill -CONT "$view_pid"
settle "$n"
kept=$(last_displacement)
key g
if gt "$kept" 8; then pass "a drag released with Shift was kept (max_displacement_mm $kept)"
else fail "Shift + release: max_displacement_mm $kept (expected the drag kept, > 8 mm)"; fi
not_displaced() { ! displaced_more_than 0.001; }
displaced_as_kept() { awk -v a="$(last_displacement)" -v b="$kept" 'BEGIN { d = a - b; exit !(d < 0.0015 && d > -0.0015) }'; }
n=$(frames)
key ctrl+z
if wait_for 60 not_displaced; then settle "$n"; pass "Ctrl+Z took the kept drag back (max_displacement_mm $(last_displacement))"
else fail "Ctrl+Z: max_displacement_mm $(last_displacement), expected 0"; fi
# The chord reaches a viewer that is not reading events (stopped), so that
# it reads Ctrl, Shift, Z and their releases in one go, as under load: the
# modifiers must be those of the Z's own event, not those after the
# releases (which would make it Z alone, or Ctrl+Z).
n=$(frames)
kill -STOP "$view_pid"; key ctrl+shift+z; sleep 0.3; kill -CONT "$view_pid"
if wait_for 60 displaced_as_kept; then settle "$n"; pass "Ctrl+Shift+Z brought it back (max_displacement_mm $(last_displacement), kept $kept)"
else fail "Ctrl+Shift+Z: max_displacement_mm $(last_displacement), expected $kept"; fi

# 6. A screenshot.
key s
wait_for 10 grep -q '^screenshot ' "$tmp/view.out"
png=$(sed -n 's/^screenshot //p' "$tmp/view.out" | tail -1)
if [ -n "$png" ] && [ -s "$png" ] && [ "$(identify -format %m "$png" 2>/dev/null)" = PNG ] &&
   gt "$(stddev "$png")" 0.05; then pass "S saved $(identify -format '%wx%h' "$png") PNG $(basename "$png")"
else fail "S did not save a PNG screenshot ($png)"; fi

# 6b. L: three slices with every frame, drawn in a 2 x 2 grid (the 3D
# frame top left, at half size); L again: back to the 3D frame alone.
n=$(frames)
key l
wait_for 60 grep -q ' slices 3$' "$tmp/view.out" || fail "L brought no frames with 3 slices"
settle "$n"
shot slices
half="$((frame_w / 2))x$((frame_h / 2))"
import -window "$window" "$tmp/slices-all.png"
convert "$tmp/slices-all.png" -crop "${half}+$((frame_w / 2))+$((frame_h / 2))" +repage "$tmp/slice-br.png"
sd=$(stddev "$tmp/slice-br.png")
if gt "$sd" 0.05 && grep -q "^frame [0-9]* $half .* slices 3$" "$tmp/view.out"; then
  pass "L shows 3 slices beside a $half 3D frame (bottom-right cell stddev $sd)"
else fail "L: bottom-right slice cell stddev $sd; frames: $(tail -1 "$tmp/view.out")"; fi

# 6c. The wheel over the axial slice (top right) scrolls it: three notches
# ask for three planes one pixel size apart, and the slice image changes.
cell() { convert "$1" -crop "${half}+$2+$3" +repage "$4"; }
cell "$tmp/slices-all.png" $((frame_w / 2)) 0 "$tmp/axial-before.png"
n=$(frames)
xdotool mousemove --window "$window" $((frame_w * 3 / 4)) $((frame_h / 4)); sleep 0.3
xdotool click --repeat 3 --delay 150 4
wait_for 30 bash -c "[ \$(grep -c 'axial=[-0-9]' '$tmp/view.out') -ge 3 ]" ||
  fail "three wheel notches over the axial slice did not set three axial positions"
settle "$n"
# Under load a frame can take longer than settle's quiet second: look again
# until the slice has changed, for up to 30 s.
axial_changed() {
  import -window "$window" "$tmp/scrolled-all.png" &&
    cell "$tmp/scrolled-all.png" $((frame_w / 2)) 0 "$tmp/axial-after.png" &&
    [ "$(changed_pixels "$tmp/axial-before.png" "$tmp/axial-after.png")" -gt 100 ]
}
wait_for 30 axial_changed
steps=$(grep -o 'axial=[-0-9.e+]*' "$tmp/view.out" | cut -d= -f2 | tail -3 |
        awk 'NR > 1 { printf "%.4f ", $1 - p } { p = $1 }')
d=$(changed_pixels "$tmp/axial-before.png" "$tmp/axial-after.png")
if echo "$steps" | awk '{ exit !($1 > 0 && ($1 - $2) < 1e-3 && ($2 - $1) < 1e-3) }' && [ "$d" -gt 100 ]; then
  pass "wheel scrolled the axial slice in equal steps ($steps mm; $d pixels changed)"
else fail "wheel over the axial slice: steps '$steps' mm, $d pixels changed"; fi

# 6d. Grab mode on a slice: pressing on the coronal slice (bottom left)
# grabs the tissue on its plane, dragging pulls it within the plane.
key g
n=$(frames)
drag 1 $((frame_w / 4)) $((frame_h * 3 / 4)) 24 -16 6
if wait_for 60 displaced_more_than 5; then
  pass "grab and drag on the coronal slice deformed the volume (max_displacement_mm $(last_displacement))"
else fail "grab on the coronal slice: max_displacement_mm $(last_displacement), expected > 5"; fi
xdotool mouseup 1
settle "$n"
key g
n=$(frames)
key l
wait_for 60 grep -q "^frame [0-9]* ${frame_w}x${frame_h} .* slices 0$" "$tmp/view.out" ||
  fail "L again did not bring back ${frame_w}x${frame_h} frames without slices"
settle "$n"

# 6e. B: the crop box, the volume's box at first. From the reset view (it
# looks along an axis), dragging the face under the centre 40 px up pushes
# it into the volume: the box sent changes and so does the frame.
n=$(frames); key v; settle "$n"
n=$(frames); key b
wait_for 15 grep -q '^settings crop [-0-9]' "$tmp/view.out" || fail "B sent no crop box"
settle "$n"
shot crop0
box0=$(grep '^settings crop [-0-9]' "$tmp/view.out" | tail -1 | cut -d' ' -f3-8)
n=$(frames)
drag 1 $((frame_w / 2)) $((frame_h / 2)) 0 -40 8; xdotool mouseup 1
settle "$n"
shot crop1
box1=$(grep '^settings crop [-0-9]' "$tmp/view.out" | tail -1 | cut -d' ' -f3-8)
moved=$(echo "$box0 $box1" | awk '{ m = 0; for (i = 1; i <= 6; ++i) { d = $(i + 6) - $i; if (d < 0) d = -d; if (d > m) m = d } print m }')
d=$(changed_pixels "$tmp/crop0.png" "$tmp/crop1.png")
if gt "$moved" 10 && [ "$d" -gt 1000 ]; then
  pass "dragging a crop face moved it $moved mm ($box0 -> $box1) and changed $d pixels"
else fail "crop face drag: moved $moved mm ($box0 -> $box1), $d pixels changed"; fi
n=$(frames); key b
wait_for 15 bash -c "tail -1 <(grep '^settings' '$tmp/view.out') | grep -q '^settings crop none'" ||
  fail "B again did not clear the crop box"
settle "$n"

# 6f. C: a clip plane facing the camera through the centre cuts the front
# away; PageUp moves it 1 mm deeper; C again removes it.
n=$(frames); key c
wait_for 15 grep -q ' clip [-0-9]' "$tmp/view.out" || fail "C sent no clip plane"
settle "$n"
shot clip
d=$(changed_pixels "$tmp/crop0.png" "$tmp/clip.png")
xdotool mousemove --window "$window" $((frame_w / 2)) $((frame_h / 2))
n=$(frames); key Page_Up; settle "$n"
offsets=$(grep -o ' clip [-0-9.e+]*' "$tmp/view.out" | tail -2 | awk '{ printf "%s ", $2 }')
step=$(echo "$offsets" | awk '{ print $2 - $1 }')
if [ "$d" -gt 1000 ] && gt "$step" 0.999 && gt 1.001 "$step"; then
  pass "C cut the front away ($d pixels changed), PageUp moved the plane $step mm ($offsets)"
else fail "clip plane: $d pixels changed, PageUp step $step mm ($offsets)"; fi
# P adds a second plane facing the orbited camera: both are sent and cut,
# and PageUp moves the newest only.
shot clip1
n=$(frames); drag 1 $((frame_w / 2)) $((frame_h / 2)) 60 0 6; xdotool mouseup 1; settle "$n"
n=$(frames); key p
wait_for 15 bash -c "tail -1 <(grep '^settings' '$tmp/view.out') | grep -q ' clip [-0-9.e+]* [-0-9.e+]* at'" ||
  fail "P sent no second clip plane: $(grep '^settings' "$tmp/view.out" | tail -1)"
settle "$n"
shot clip2
d=$(changed_pixels "$tmp/clip1.png" "$tmp/clip2.png")
before=$(grep '^settings' "$tmp/view.out" | tail -1 | grep -o ' clip [-0-9.e+]* [-0-9.e+]*')
n=$(frames); key Page_Up; settle "$n"
after=$(grep '^settings' "$tmp/view.out" | tail -1 | grep -o ' clip [-0-9.e+]* [-0-9.e+]*')
moved=$(echo "$before $after" | awk '{ printf "%g %g", $5 - $2, $6 - $3 }')
if [ "$d" -gt 1000 ] && [ "${moved% *}" = 0 ] && gt "${moved#* }" 0.999 && gt 1.001 "${moved#* }"; then
  pass "P added a second clip plane (orbit + plane: $d pixels changed); PageUp moved the newest only ($before -> $after)"
else fail "second clip plane: $d pixels changed, offsets $before -> $after"; fi
n=$(frames); key c; settle "$n"

# 7. Resizing the window asks for frames of the new size (the frame area is
# the window less the status bar).
n=$(frames)
xdotool windowsize "$window" 320 300
bar=$(( $(identify -format %h "$tmp/first-window.png") - frame_h ))
want="320x$((300 - bar))"
if wait_for 60 grep -q "^frame [0-9]* $want " "$tmp/view.out"; then pass "resize to 320x300 brought $want frames"
else fail "no $want frame after resizing the window to 320x300"; fi
settle "$n"
frame_w=320 frame_h=$((300 - bar))

# 8. The server dies: a red banner says so; it comes back on the same port
# and state directory: the viewer reopens its case, frames again, with the
# same displacement.
before_kill=$(last_displacement)
kill -KILL "$server_pid"; wait "$server_pid" 2>/dev/null; server_pid=""
wait_for 15 grep -q 'connection lost' "$tmp/view.err" || fail "vpm-view did not report the lost connection"
sleep 0.5
shot lost
red=$(red_rows "$tmp/lost-window.png")
if [ "$red" -gt 20 ]; then pass "lost connection shown in the window (a red banner $red rows high)"
else fail "no lost-connection banner in the window ($red red rows)"; fi
n=$(frames)
start_server "127.0.0.1:$port"
wait_for 90 connects_at_least 2 ||
  fail "vpm-view did not reconnect to the restarted server"
settle "$n" || fail "no frame from the restarted server"
shot back
red=$(red_rows "$tmp/back-window.png") sd=$(stddev "$tmp/back.png")
if [ "$red" = 0 ] && gt "$sd" 0.05; then pass "reconnected and streaming again (no banner, stddev $sd)"
else fail "after the restart: $red red banner rows, frame stddev $sd"; fi
if grep -q 'vpm-view: case case-[0-9a-f]* open in session' "$tmp/view.err" &&
   [ "$(last_displacement)" = "$before_kill" ]; then
  pass "reopened its case after the restart (max_displacement_mm $before_kill before, $(last_displacement) after)"
else fail "after the restart: case reopened? $(grep -c 'open in session' "$tmp/view.err"); max_displacement_mm $before_kill before, $(last_displacement) after"; fi

# 8b. F2: the cases panel lists my cases; R renames the viewer's case,
# Return opens another (the viewer moves to its session), Delete twice
# deletes one. Checked against the server with the vpm command line.
vpm_cli() { VPM_TOKEN="$token" "$build/client/vpm" --server "127.0.0.1:$port" "$@"; }
ours=$(sed -n 's/^vpm-view: case \(case-[0-9a-f]*\) open in session.*/\1/p' "$tmp/view.err" | tail -1)
vol=$(vpm_cli volume load "phantom:abdomen?size=128" | sed -n 's/.*"volume_id": "\([^"]*\)".*/\1/p')
other=$(vpm_cli session open --volume-id "$vol" | sed -n 's/.*"case_id": "\([^"]*\)".*/\1/p')
count_lines() { grep -c "^$1" "$tmp/view.out"; }
lists=$(count_lines 'cases 2')
key F2
wait_for 20 bash -c "[ \$(grep -c '^cases 2' '$tmp/view.out') -gt $lists ]" ||
  fail "F2 did not list the 2 cases ($(grep '^cases' "$tmp/view.out" | tail -1))"
shot cases
key r; xdotool type --delay 40 "kidney plan"; key Return
wait_for 20 grep -q "^notice case renamed $ours kidney plan" "$tmp/view.out" ||
  fail "R + typing did not rename $ours: $(grep '^notice' "$tmp/view.out" | tail -1)"
if vpm_cli case show "$ours" --json | grep -q '"title": "kidney plan"'; then
  pass "the cases panel (F2) listed 2 cases and renamed the viewer's ($ours) to 'kidney plan'"
else fail "after the panel's rename the server has: $(vpm_cli case show "$ours" --json | grep title)"; fi
lists=$(count_lines 'cases 2')
wait_for 20 bash -c "[ \$(grep -c '^cases 2' '$tmp/view.out') -gt $((lists - 1)) ]"
key Down; key Return
if wait_for 60 grep -q "^vpm-view: case $other open in session" "$tmp/view.err"; then
  pass "Return opened the other case ($other) in the viewer"
else fail "Return did not open $other: $(grep 'open in session' "$tmp/view.err" | tail -1)"; fi
n=$(frames); settle "$n"
key F2
wait_for 20 bash -c "[ \$(grep -c '^cases 2' '$tmp/view.out') -gt $lists ]"
# The panel opens on the viewer's case and lists as the server does (newest
# change first): move to ours.
at_other=$(vpm_cli case list --json | grep -o '"case_id": "[^"]*"' | grep -n "$other" | cut -d: -f1)
at_ours=$(vpm_cli case list --json | grep -o '"case_id": "[^"]*"' | grep -n "$ours" | cut -d: -f1)
if [ "$at_ours" -lt "$at_other" ]; then key Up; else key Down; fi
key Delete
sleep 0.5
if grep -q "^notice case deleted" "$tmp/view.out"; then fail "one Delete deleted a case"; fi
key Delete
wait_for 20 grep -q "^notice case deleted $ours" "$tmp/view.out" ||
  fail "Delete twice did not delete $ours: $(grep '^notice' "$tmp/view.out" | tail -1)"
left=$(vpm_cli case list --json | grep -o '"case_id": "[^"]*"' | tr '\n' ' ')
if [ "$left" = "\"case_id\": \"$other\" " ]; then pass "Delete twice deleted $ours; the server keeps $other only"
else fail "after the panel's delete the server lists: $left"; fi
key F2

# 9. Quit.
key q
if wait_for 15 bash -c "! kill -0 $view_pid 2>/dev/null"; then
  wait "$view_pid"; rc=$?
  view_pid=""
  if [ "$rc" = 0 ]; then pass "q quit (exit status 0)"; else fail "vpm-view exited with $rc"; fi
else
  fail "q did not quit vpm-view"
fi

median() { sort -n | awk '{ a[NR] = $1 } END { if (NR) print a[int((NR + 1) / 2)]; else print "-" }'; }
for quality in still interactive; do
  echo "$quality frames: $(awk -v q=$quality '$1 == "frame" && $6 == q' "$tmp/view.out" | wc -l)," \
    "median server total_ms $(awk -v q=$quality '$1 == "frame" && $6 == q { print $10 }' "$tmp/view.out" | median)," \
    "median rtt_ms $(awk -v q=$quality '$1 == "frame" && $6 == q && $12 >= 0 { print $12 }' "$tmp/view.out" | median)"
done
if [ $failures -gt 0 ]; then
  echo "--- vpm-view stderr"; cat "$tmp/view.err"
  echo "$failures check(s) failed"; exit 1
fi
echo "all vpm-view end-to-end checks passed"
