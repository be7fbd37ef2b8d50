#!/bin/bash
# Byte-identity check between two builds of gseg (issue #17: "nothing a user sees changes"):
#
#   tests/compare_builds.sh REF NEW [WORK]
#
# REF and NEW are build folders (with bin/ inside) or bin folders. Every main route is run once
# with each build's tools on the shared data (../shared/data: the 20 labelled scans, sequence 00,
# the three drives of semantickitti-drives) and on mrpt-common's rawlogs
# (/usr/share/mrpt/datasets/*.rawlog), in WORK/ref and WORK/new (default: a fresh temporary
# folder), with the same relative paths and the same config files (this checkout's config/);
# then every output file and every exit code is compared byte for byte (gzip files, rawlogs,
# scenes and simple maps, by the bytes they decode to: gseg's gzip members (#35) compress the same
# objects into other bytes than one zlib stream did):
#   gseg segment --labels-out (fixed and auto height), gseg eval --report CSVs (without the ms
#   column) and the range plot, kitti2rawlog (rawlog + simplemap), rawlog-gseg, rawlog-octomap (the
#   six map files; raw and pre-segmented input), gseg-observations2map (the six files).
# Prints one line per differing file and a summary; exit 0 when everything is identical, 1 when
# something differs, 2 on bad usage. Data that is absent is skipped with a message.
set -u

usage() { echo "usage: $0 REF_BUILD_OR_BIN NEW_BUILD_OR_BIN [WORK_DIR]" >&2; exit 2; }
[ $# -ge 2 ] && [ $# -le 3 ] || usage

bin_of() {
    if [ -x "$1/bin/gseg" ]; then (cd "$1/bin" && pwd)
    elif [ -x "$1/gseg" ]; then (cd "$1" && pwd)
    else echo "$0: $1: no gseg executable in it or in its bin/" >&2; exit 2
    fi
}
REF=$(bin_of "$1") || exit 2
NEW=$(bin_of "$2") || exit 2
src=$(cd "$(dirname "$0")/.." && pwd)
data=$(cd "$src/.." && pwd)/shared/data
datasets=/usr/share/mrpt/datasets
if [ $# -eq 3 ]; then
    WORK=$3
    mkdir -p "$WORK" || exit 2
    [ -z "$(ls -A "$WORK")" ] || { echo "$0: $WORK is not empty" >&2; exit 2; }
else
    WORK=$(mktemp -d /tmp/gseg_compare.XXXXXX)
fi
WORK=$(cd "$WORK" && pwd)
cfg=$src/config

# run_both NAME TOOL ARGS...: runs "$BIN/TOOL ARGS" in WORK/ref and WORK/new (same relative paths),
# keeps the exit code in exit_codes.txt and the stderr in log/NAME.err.
run_both() {
    local name=$1 tool=$2
    shift 2
    for side in ref new; do
        local bin=$REF
        [ $side = new ] && bin=$NEW
        (cd "$WORK/$side" && "$bin/$tool" "$@" >"log/$name.out" 2>"log/$name.err")
        echo "$name: exit $?" >>"$WORK/$side/exit_codes.txt"
    done
}

mkdir -p "$WORK/ref/log" "$WORK/new/log"
for side in ref new; do
    (cd "$WORK/$side" && mkdir -p labels labels_auto eval rawlogs split maps o2m)
done
printf '0 0 0 0 0 0 0 1\n' | tee "$WORK/ref/stationary.tum" >"$WORK/new/stationary.tum"

# 1. gseg segment --labels-out: the 20 labelled scans (fixed and auto height) and the VLP-16 scan.
scans=()
for root in semantickitti semantickitti-extra; do
    for label in "$data/$root"/sequences/*/labels/*.label; do
        [ -f "$label" ] || continue
        seq=$(basename "$(dirname "$(dirname "$label")")")
        frame=$(basename "$label" .label)
        scans+=("$data/$root/sequences/$seq/velodyne/$frame.bin")
    done
done
[ ${#scans[@]} -gt 0 ] || echo "compare_builds: no labelled scans under $data: skipped them"
for scan in "${scans[@]}"; do
    seq=$(basename "$(dirname "$(dirname "$scan")")")
    name=${seq}_$(basename "$scan" .bin)
    run_both "segment_$name" gseg segment -q -i "$scan" -c "$cfg/kitti_hdl64.yaml" --labels-out "labels/$name.labels"
    run_both "segment_auto_$name" gseg segment -q -i "$scan" -c "$cfg/auto_height.yaml" --labels-out "labels_auto/$name.labels"
done
vlp16=$datasets/test_velodyne_VLP16.rawlog
if [ -f "$vlp16" ]; then
    run_both segment_vlp16 gseg segment -q -i "$vlp16" -c "$cfg/vlp16.yaml" --labels-out labels/vlp16.labels \
        --ply-out labels/vlp16.ply
else
    echo "compare_builds: $vlp16 missing (apt-get install mrpt-common): skipped it"
fi

# 2. gseg eval --report (the ms column is dropped below).
for root in semantickitti semantickitti-extra; do
    [ -d "$data/$root" ] || continue
    run_both "eval_$root" gseg eval -q -i "$data/$root" --report "eval/$root" --threads 2
    run_both "eval_auto_$root" gseg eval -q -i "$data/$root" -c "$cfg/auto_height.yaml" --report "eval/${root}_auto" --threads 2
done

# 3. kitti2rawlog: sequence 00 and the drives (rawlog + simplemap).
drives=()
[ -f "$data/semantickitti/sequences/00/poses.txt" ] && drives+=("seq00:$data/semantickitti/sequences/00")
for d in "$data"/semantickitti-drives/sequences/*; do
    [ -f "$d/poses.txt" ] && drives+=("drive$(basename "$d"):$d")
done
[ ${#drives[@]} -gt 0 ] || echo "compare_builds: no drives under $data: skipped kitti2rawlog and the maps of drives"
for entry in "${drives[@]}"; do
    name=${entry%%:*} dir=${entry#*:}
    run_both "kitti2rawlog_$name" kitti2rawlog -q -i "$dir" -o "rawlogs/$name.rawlog" --simplemap "rawlogs/$name.simplemap"
done

# 4. rawlog-gseg and rawlog-octomap (the six map files): every mrpt-common rawlog (auto height;
# maps with one identity pose), and every drive (fixed and auto height, the pre-segmented rawlog,
# one worker thread).
for f in "$datasets"/*.rawlog; do
    [ -f "$f" ] || continue
    name=$(basename "$f" .rawlog | tr -c 'A-Za-z0-9_.\n-' '_')
    run_both "rawlog-gseg_$name" rawlog-gseg -q -i "$f" -o "split/$name.rawlog" -c "$cfg/vlp16.yaml"
    run_both "rawlog-octomap_$name" rawlog-octomap -q -i "$f" -o "maps/$name" -c "$cfg/vlp16.yaml" \
        --poses stationary.tum --pose-tolerance 1e12
done
for entry in "${drives[@]}"; do
    name=${entry%%:*} in=rawlogs/${entry%%:*}.rawlog
    run_both "rawlog-gseg_$name" rawlog-gseg -q -i "$in" -o "split/$name.rawlog" -c "$cfg/kitti_hdl64.yaml"
    run_both "rawlog-gseg_auto_$name" rawlog-gseg -q -i "$in" -o "split/${name}_auto.rawlog" -c "$cfg/auto_height.yaml"
    run_both "rawlog-octomap_$name" rawlog-octomap -q -i "$in" -o "maps/$name" -c "$cfg/kitti_hdl64.yaml"
    run_both "rawlog-octomap_auto_$name" rawlog-octomap -q -i "$in" -o "maps/${name}_auto" -c "$cfg/auto_height.yaml"
    run_both "rawlog-octomap_split_$name" rawlog-octomap -q -i "split/$name.rawlog" -o "maps/${name}_split"
    run_both "rawlog-octomap_1thread_$name" rawlog-octomap -q -i "$in" -o "maps/${name}_1thread" --threads 1
done

# 5. gseg-observations2map (needs observations2map of mrpt-apps).
if command -v observations2map >/dev/null; then
    for entry in "${drives[@]}"; do
        name=${entry%%:*}
        run_both "o2m_$name" gseg-observations2map -q -c "$cfg/octomap_maps.ini" -i "rawlogs/$name.simplemap" -o "o2m/$name"
    done
else
    echo "compare_builds: observations2map missing (apt-get install mrpt-apps): skipped gseg-observations2map"
fi

# The ms column of eval's CSVs is a timing: drop it (by its header) on both sides.
for side in ref new; do
    for csv in "$WORK/$side"/eval/*.csv; do
        [ -f "$csv" ] || continue
        awk -F, -v OFS=, 'NR == 1 { for (i = 1; i <= NF; ++i) if ($i ~ /(^|_)ms$/) drop[i] = 1 }
            { line = ""; n = 0; for (i = 1; i <= NF; ++i) if (!drop[i]) line = line (n++ ? OFS : "") $i; print line }' \
            "$csv" >"$csv.noms" && mv "$csv.noms" "$csv"
    done
    rm -f "$WORK/$side"/eval/*_table.md  # holds ms/scan; its figures are those of the CSVs
done

# Compare: every file (logs apart), both ways.
same_file() {
    cmp -s "$1" "$2" && return 0
    case "$1" in *.rawlog | *.3Dscene | *.simplemap) cmp -s <(zcat -f -- "$1") <(zcat -f -- "$2") ;; *) return 1 ;; esac
}
differ=0 same=0
while IFS= read -r rel; do
    if [ ! -f "$WORK/new/$rel" ]; then
        echo "only in the reference build's outputs: $rel"
        differ=$((differ + 1))
    elif ! same_file "$WORK/ref/$rel" "$WORK/new/$rel"; then
        echo "differs: $rel ($(cmp "$WORK/ref/$rel" "$WORK/new/$rel" 2>&1 | head -1))"
        differ=$((differ + 1))
    else
        same=$((same + 1))
    fi
done < <(cd "$WORK/ref" && find . -type f ! -path './log/*' | sort)
while IFS= read -r rel; do
    [ -f "$WORK/ref/$rel" ] || { echo "only in the new build's outputs: $rel"; differ=$((differ + 1)); }
done < <(cd "$WORK/new" && find . -type f ! -path './log/*' | sort)
echo "compare_builds: $same file(s) identical, $differ differ (outputs in $WORK; stderr of each run in */log/)"
[ $differ -eq 0 ]
