#!/bin/bash
# Screenshot of a viewer under Xvfb, as a new user sees it at first open (how the README's viewer
# pictures were taken).
# usage: docs/screenshot.sh OUT.png ZOOM_OUT_STEPS viewer-command...
#   docs/screenshot.sh docs/sceneviewer_seq00_map.png 0 SceneViewer3D build/out/seq00_traversability.3Dscene
#   docs/screenshot.sh docs/cloudcompare_vlp16.png -12 CloudCompare build/out/vlp16.ply
# ZOOM_OUT_STEPS: mouse-wheel steps away from the scene before the picture (0: the view the file
# opens with; negative: towards it). CloudCompare's PLY dialog ("Ply File Open") is accepted as it comes (Apply): what a
# user who clicks Apply sees. Needs xvfb, xdotool and imagemagick; software OpenGL
# (LIBGL_ALWAYS_SOFTWARE=1). The picture is the whole 1280x960 screen, the viewer's window
# filling it, saved at 960x720 in 256 colours.
set -euo pipefail
out=$1 steps=$2
shift 2
export LIBGL_ALWAYS_SOFTWARE=1
xvfb-run -a -s "-screen 0 1280x960x24" bash -c '
  steps=$1 out=$2; shift 2
  "$@" >/dev/null 2>&1 & pid=$!
  w=
  for i in $(seq 1 120); do
    w=$(xdotool search --onlyvisible --pid $pid 2>/dev/null | head -1 || true)
    [ -n "$w" ] && break
    sleep 0.5
  done
  [ -n "$w" ] || { echo "screenshot.sh: no window of $1" >&2; kill $pid; exit 1; }
  sleep 4
  d=$(xdotool search --onlyvisible --name "^Ply File Open$" 2>/dev/null | head -1 || true)
  if [ -n "$d" ]; then xdotool windowactivate --sync $d key Return 2>/dev/null || xdotool key Return; sleep 4; fi
  w=$(xdotool search --onlyvisible --pid $pid 2>/dev/null | head -1)
  xdotool windowmove $w 0 0 windowsize $w 1280 960
  sleep 3
  xdotool mousemove 640 480
  button=5; [ "$steps" -lt 0 ] && button=4 steps=$((-steps))
  for k in $(seq 1 $steps); do xdotool click $button; sleep 0.15; done
  sleep 3
  import -window root "$out"
  kill $pid' _ "$steps" "$out" "$@"
# Small enough for the repository: 960x720, 256 colours.
convert "$out" -resize 960x720 -dither None -colors 256 "PNG8:$out"
