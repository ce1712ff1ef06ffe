#!/usr/bin/env bash
# strata's full-quality build against Embree 3's medium-quality build of the
# same triangles on the same threads (issue 58's target: at most 0.6 of
# Embree's time), alternating, for each thread count asked.
#
#   tools/bench_build_vs_embree.sh STRATA EMBREE_TRACE MESH.ply [ROUNDS] [THREADS...]
#
#   STRATA        a strata binary
#   EMBREE_TRACE  tools/embree/embree_trace (make -C tools/embree); its
#                 libembree3.so.3 and libtbb.so.12 found through
#                 LD_LIBRARY_PATH where they are not installed
#   MESH.ply      a PLY or OBJ mesh (dragon-sub2.ply from
#                 `tools/fetch-assets --subdivide 2`)
#   ROUNDS        rounds per thread count (default 3)
#   THREADS       thread counts (default: 2). Two threads run pinned to
#                 CPUs 0 and 1 (taskset), as on a two-core machine.
#
# strata's time is `render --spp 1 --bvh-quality medium --stats`'s
# bvh_build_s (its triangle boxes included, as Embree's build includes
# its own); Embree's is the harness's "BVH" seconds (rtcCommitScene at
# RTC_BUILD_QUALITY_MEDIUM). Prints one line a round and the median
# ratio a thread count. Needs python3 with numpy (to write the triangles
# for Embree) and, for two threads, taskset.
set -euo pipefail

if [ $# -lt 3 ]; then
    sed -n '2,23p' "$0" | sed 's/^# \{0,1\}//'
    exit 2
fi
strata=$1 embree=$2 mesh=$3 rounds=${4:-3}
shift $(($# < 4 ? $# : 4))
threads_list=${*:-2}
for f in "$strata" "$embree" "$mesh"; do
    [ -e "$f" ] || { echo "error: $f: no such file" >&2; exit 2; }
done
for n in "$rounds" $threads_list; do
    [[ $n =~ ^[1-9][0-9]*$ ]] || { echo "error: '$n': ROUNDS and THREADS are whole numbers from 1" >&2; exit 2; }
done
case " $threads_list " in
*" 2 "*) command -v taskset >/dev/null || { echo "error: taskset (util-linux) is needed to pin two threads to CPUs 0 and 1" >&2; exit 2; } ;;
esac
python3 -c "import numpy" 2>/dev/null || { echo "error: python3 cannot import numpy (needed to write the triangles for Embree)" >&2; exit 2; }
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

# MESH.tris for the harness, read and written by the tools that
# bench_embree.py uses (validate_embree.load_mesh: OBJ or PLY, in strata's
# triangle order; bench_embree.write_tris).
python3 - "$(dirname "$0")" "$mesh" "$work/mesh.tris" <<'EOF'
import sys
tools, path, out = sys.argv[1:]
sys.path.insert(0, tools)
from validate_embree import InputError, load_mesh
from bench_embree import write_tris
try:
    vertices, triangles = load_mesh(path)
except InputError as e:
    print(f"error: {e}", file=sys.stderr)
    sys.exit(2)
write_tris(vertices, triangles, out)
EOF
"$strata" rays random "$mesh" -n 1000 -o "$work/rays.bin" --quiet

echo "cpu: $(lscpu | sed -n 's/^Model name: *//p' | head -1), $(nproc) CPUs; $(basename "$mesh")"
for t in $threads_list; do
    pin=()
    [ "$t" = 2 ] && pin=(taskset -c 0,1)
    : >"$work/ratios"
    for round in $(seq "$rounds"); do
        "${pin[@]}" "$strata" render "$mesh" --width 64 --height 48 --spp 1 --threads "$t" \
            --bvh-quality medium --quiet --stats "$work/s.json" -o "$work/image.png"
        s=$(python3 -c "import json, sys; print(json.load(open(sys.argv[1]))['time']['bvh_build_s'])" "$work/s.json")
        e=$("${pin[@]}" "$embree" "$work/mesh.tris" "$work/rays.bin" --quality medium --threads "$t" \
            | sed -n 's/.*BVH \([0-9.]*\) s.*/\1/p')
        [ -n "$e" ] || { echo "error: $embree printed no BVH time" >&2; exit 1; }
        awk -v s="$s" -v e="$e" 'BEGIN {print s / e}' >>"$work/ratios"
        printf 'threads %2d round %d: strata medium %.3f s, Embree medium %.3f s, ratio %.3f\n' \
            "$t" "$round" "$s" "$e" "$(tail -1 "$work/ratios")"
    done
    printf 'threads %2d: median ratio %.3f (target 0.6)\n' "$t" \
        "$(sort -g "$work/ratios" | awk '{a[NR] = $1} END {print (NR % 2) ? a[(NR + 1) / 2] : (a[NR / 2] + a[NR / 2 + 1]) / 2}')"
done
