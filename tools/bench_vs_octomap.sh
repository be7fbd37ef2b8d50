#!/bin/sh
# rawlog-octomap against plain liboctomap on one drive, side by side in one run (issue #35).
#
#   tools/bench_vs_octomap.sh [-b BUILD] [-s SEQUENCE_DIR] [-r REPEAT] [-n ROUNDS] [-w WORKDIR]
#
# Makes the drive with kitti2rawlog (the frames of SEQUENCE_DIR REPEAT times along a continuing
# trajectory; default sequence 00 of ../shared/data/semantickitti, REPEAT 100: the 600-scan
# drive, 864 MB, kept in WORKDIR and reused by the next run), then runs `rawlog-octomap --bench
# ROUNDS`: plain OctoMap (every scan's points in the world frame with the same poses,
# OcTree::insertPointCloud(cloud, sensor origin, maxRange, lazy = false, discretize = true),
# writeBinary(); rawlog-octomap's resolution and maxRange) and rawlog-octomap (segmentation, ray
# casting, all 17 files), rounds alternating which runs first. Prints the table with both wall
# times, the median ratio, rawlog-octomap's time per step, and the load average before and after
# (the machine's other work slows both alike within a round, not across runs).
# Exit: 0 done, 1 a step failed, 2 bad usage.
set -eu

here=$(cd "$(dirname "$0")/.." && pwd)
build="$here/build"
sequence="$here/../shared/data/semantickitti/sequences/00"
repeat=100
rounds=1
work="${TMPDIR:-/tmp}/gseg_bench_vs_octomap"

usage() {
    echo "bench_vs_octomap.sh: $1" >&2
    echo "usage: tools/bench_vs_octomap.sh [-b BUILD] [-s SEQUENCE_DIR] [-r REPEAT] [-n ROUNDS] [-w WORKDIR]" >&2
    exit 2
}
while getopts "b:s:r:n:w:h" opt; do
    case "$opt" in
        b) build=$OPTARG ;;
        s) sequence=$OPTARG ;;
        r) repeat=$OPTARG ;;
        n) rounds=$OPTARG ;;
        w) work=$OPTARG ;;
        h) sed -n '2,15p' "$0" | sed 's/^# \{0,1\}//'; exit 0 ;;
        *) usage "unknown option" ;;
    esac
done
shift $((OPTIND - 1))
[ $# -eq 0 ] || usage "unexpected argument '$1'"
for tool in kitti2rawlog rawlog-octomap; do
    [ -x "$build/bin/$tool" ] || usage "$build/bin/$tool: not built (cmake --build build --target $tool)"
done
[ -f "$sequence/poses.txt" ] || usage "$sequence: not a KITTI sequence with poses.txt"

mkdir -p "$work"
drive="$work/$(basename "$sequence")_x$repeat.rawlog"
if [ ! -s "$drive" ]; then
    echo "making $drive (kitti2rawlog --repeat $repeat) ..."
    "$build/bin/kitti2rawlog" -q -w -i "$sequence" --repeat "$repeat" -o "$drive"
fi
echo "load average before: $(cut -d' ' -f1-3 /proc/loadavg), $(nproc) core(s)"
"$build/bin/rawlog-octomap" -i "$drive" -o "$work/bench" -c "$here/config/kitti_hdl64.yaml" --bench "$rounds" -w
echo "load average after: $(cut -d' ' -f1-3 /proc/loadavg)"
