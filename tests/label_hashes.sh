#!/bin/bash
# Regenerates tests/label_hashes.txt, the golden label hashes of tests/core/test_label_lock.cpp (#21):
#
#   tests/label_hashes.sh BUILD_DIR
#
# BUILD_DIR: a build of this checkout with test_label_lock built (cmake --build BUILD_DIR --target
# test_label_lock). It runs the test in its writing mode (GSEG_LABEL_HASHES_OUT) and replaces the
# file. Only a deliberate change of the segmenter's labels regenerates it, and the commit says why.
set -eu
[ $# -eq 1 ] || { echo "usage: $0 BUILD_DIR" >&2; exit 2; }
src=$(cd "$(dirname "$0")/.." && pwd)
bin=$1/bin/test_label_lock
[ -x "$bin" ] || { echo "$0: $bin: not built" >&2; exit 2; }
tmp=$(mktemp /tmp/label_hashes.XXXXXX)
trap 'rm -f "$tmp" "$tmp.body"' EXIT
GSEG_LABEL_HASHES_OUT="$tmp.body" "$bin" >/dev/null
{
    echo "# Golden labels of the segmenter (tests/core/test_label_lock.cpp): case, points, FNV-1a 64 of the label"
    echo "# bytes (one per point, 1 ground, 0 non-ground). kitti/ROOT/SEQ/FRAME: ../shared/data/ROOT's labelled"
    echo "# scans with config/kitti_hdl64.yaml (fixed) and config/auto_height.yaml (auto); vlp16/: mrpt-common's"
    echo "# test_velodyne_VLP16.rawlog with config/kitti_hdl64.yaml and config/vlp16.yaml; scene/NAME: the"
    echo "# simulated scenes of tests/support/scenes.cpp with their true height (fixed) and distToGround: auto."
    echo "# Regenerate: tests/label_hashes.sh BUILD_DIR, only for a deliberate change of labels, and say why"
    echo "# in the commit. Generated at $(git -C "$src" rev-parse --short HEAD) (labels of main 8a37f34)."
    sort "$tmp.body"
} >"$tmp"
mv "$tmp" "$src/tests/label_hashes.txt"
echo "wrote $src/tests/label_hashes.txt ($(grep -vc '^#' "$src/tests/label_hashes.txt") cases)"
