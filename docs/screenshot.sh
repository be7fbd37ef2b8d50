#!/bin/bash
# Screenshot of a viewer under Xvfb (how the README's viewer pictures were taken).
# usage: docs/screenshot.sh OUT.png ZOOM_OUT_STEPS viewer-command...
#   docs/screenshot.sh docs/sceneviewer_seq00_map.png 28 SceneViewer3D build/out/seq00_traversability.3Dscene
# Needs xvfb, xdotool and imagemagick; software OpenGL (LIBGL_ALWAYS_SOFTWARE=1).
set -euo pipefail
out=$1 steps=$2
shift 2
export LIBGL_ALWAYS_SOFTWARE=1
xvfb-run -a -s "-screen 0 1200x850x24" bash -c '
  steps=$1 out=$2; shift 2
  "$@" >/dev/null 2>&1 & pid=$!
  w=
  for i in $(seq 1 120); do
    w=$(xdotool search --onlyvisible --pid $pid 2>/dev/null | head -1 || true)
    [ -n "$w" ] && break
    sleep 0.5
  done
  [ -n "$w" ] || { echo "no window" >&2; kill $pid; exit 1; }
  sleep 4
  xdotool windowmove $w 0 0 windowsize $w 1200 850
  sleep 2
  xdotool mousemove 640 420
  for k in $(seq 1 $steps); do xdotool click 5; sleep 0.15; done
  sleep 3
  import -window root "$out"
  kill $pid' _ "$steps" "$out" "$@"
