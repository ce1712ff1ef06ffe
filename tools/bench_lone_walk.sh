#!/usr/bin/env bash
# One ray at a time on the dragon: strata's AVX2 and AVX-512 kernels against
# native Embree's rtcIntersect1 / rtcOccluded1 loop, one thread, every
# `strata rays` kind, closest hit and occlusion (docs/performance.md,
# "AVX-512 by runtime dispatch"). Runs in about 2 minutes on a 16-core
# Xeon; needs no network and no Python package (python3 alone converts the
# PLY for Embree).
#
#   tools/bench_lone_walk.sh STRATA EMBREE_TRACE DRAGON.ply [N] [RUNS] [QUALITY]
#
#   STRATA        a strata binary (built for x86-64-v3; `STRATA_SIMD` picks
#                 its kernel)
#   EMBREE_TRACE  tools/embree/embree_trace, built against Embree 3; its
#                 libembree3.so.3 and libtbb.so.12 found through
#                 LD_LIBRARY_PATH (set it to their folder)
#   DRAGON.ply    assets/dragon.ply (ASCII, 871,414 triangles)
#   N             rays of each kind (default 100000)
#   RUNS          alternating runs per row, the median taken (default 3)
#   QUALITY       strata's --bvh-quality (default high: Embree builds its
#                 high-quality tree, so both walk their best tree; auto
#                 picks by the mesh's size)
#
# Writes its ray files to a temporary folder, removed at the end. Per row:
# Mrays/s of strata avx2, strata avx512 (median of RUNS processes, each the
# median of 3 passes) and Embree (the median of RUNS × 3 passes of one
# build), run in turn, then strata / Embree for each kernel and the
# geometric means. The first lines name the CPU and the tree and one-ray
# kernel Embree built (BVH4 on some Xeons).
set -euo pipefail

if [ $# -lt 3 ]; then
    sed -n '2,28p' "$0" | sed 's/^# \{0,1\}//'
    exit 2
fi
strata=$1 embree=$2 mesh=$3 n=${4:-100000} runs=${5:-3} quality=${6:-high}
for f in "$strata" "$embree" "$mesh"; do
    [ -e "$f" ] || { echo "error: $f: no such file" >&2; exit 2; }
done
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

echo "cpu: $(lscpu | sed -n 's/^Model name: *//p' | head -1)"
printf 'v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n' >"$work/probe.obj"
if STRATA_SIMD=avx512 "$strata" rays random "$work/probe.obj" -n 1 -o "$work/probe.rays" --quiet 2>/dev/null; then
    has512=1 && echo "strata: avx2 and avx512 kernels"
else
    has512=0 && echo "strata: avx2 kernel only (this CPU lacks AVX-512: its column stays empty)"
fi

kinds="random camera grazing edges inside"
"$strata" rays all "$mesh" -n "$n" --seed 1 -o "$work/all.rays" --quiet
i=0
for kind in $kinds; do
    dd if="$work/all.rays" of="$work/$kind.rays" bs=1M iflag=skip_bytes,count_bytes \
        skip=$((i * n * 32)) count=$((n * 32)) status=none
    i=$((i + 1))
done

# MESH.tris for the harness: u32 vertex and triangle counts, f32 xyz, u32
# indices, triangles in file order (strata's numbering).
python3 - "$mesh" "$work/dragon.tris" <<'EOF'
import struct, sys
from array import array
with open(sys.argv[1], "rb") as f:
    nv = nf = None
    while True:
        line = f.readline().decode().strip()
        if line.startswith("element vertex"): nv = int(line.split()[2])
        if line.startswith("element face"): nf = int(line.split()[2])
        if line == "end_header": break
    verts = array("f")
    for _ in range(nv):
        verts.extend(float(x) for x in f.readline().split()[:3])
    tris = array("I")
    for _ in range(nf):
        w = f.readline().split()
        assert w[0] == b"3", "triangles only"
        tris.extend(int(x) for x in w[1:4])
with open(sys.argv[2], "wb") as out:
    out.write(struct.pack("<II", nv, nf))
    verts.tofile(out)
    tris.tofile(out)
EOF

# Embree: built once (high quality), then passes on request (--serve).
coproc EMB { "$embree" "$work/dragon.tris" "$work/all.rays" --serve --verbose --threads 1 2>"$work/embree.log"; }
read -r ready _ <&"${EMB[0]}"
[ "$ready" = ready ] || { echo "error: $embree did not start:" >&2; cat "$work/embree.log" >&2; exit 1; }
tree=$(awk '$1 == "building" {t = $2} $1 == "intersector1" && $2 == "=" {k = $3}
    $3 == "sah" && $4 == "=" && !($1 in sah) {sah[$1] = $5}
    END {printf "%s (SAH %s: nodes %s, leaves %s), one-ray kernel %s\n", t, sah["total"], sah["getAABBNodes"], sah["leaves"], k}' "$work/embree.log")
echo "Embree: $tree"
# strata's tree in the same measure (`strata trace --tree`).
echo "strata: --bvh-quality $quality, $("$strata" trace "$mesh" --rays "$work/random.rays" --hits "$work/tree.hits" \
    --bvh-quality "$quality" --quiet --tree | sed 's/^tree: //')"

median() { sort -g | awk '{a[NR] = $1} END {print (NR % 2) ? a[(NR + 1) / 2] : (a[NR / 2] + a[NR / 2 + 1]) / 2}'; }
strata_rate() { # kernel kind query-flag
    STRATA_SIMD=$1 "$strata" trace "$mesh" --rays "$work/$2.rays" --hits "$work/$2.$1.hits" \
        --threads 1 --one-at-a-time --repeats 3 --bvh-quality "$quality" $3 | sed 's/.*= \([0-9.]*\) Mrays\/s.*/\1/'
}
embree_rate() { # first query
    echo "$1 $n $2 single 1" >&"${EMB[1]}"
    read -r secs _ <&"${EMB[0]}"
    awk -v n="$n" -v s="$secs" 'BEGIN {print n / s / 1e6}'
}

printf '%-8s %-9s %9s %9s %9s %8s %8s\n' kind query avx2 avx512 Embree avx2/E avx512/E
i=0
rows=$work/rows
for kind in $kinds; do
    for query in closest occlusion; do
        flag=$([ $query = occlusion ] && echo --occlusion || true)
        : >"$work/a" && : >"$work/b" && : >"$work/e"
        for _ in $(seq "$runs"); do
            strata_rate avx2 "$kind" "$flag" >>"$work/a"
            [ $has512 = 0 ] || strata_rate avx512 "$kind" "$flag" >>"$work/b"
            for _ in 1 2 3; do embree_rate $((i * n)) $query >>"$work/e"; done
        done
        a=$(median <"$work/a") e=$(median <"$work/e")
        b=$([ -s "$work/b" ] && median <"$work/b" || echo nan)
        echo "$kind $query $a $b $e" >>"$rows"
        [ $has512 = 0 ] || cmp -s "$work/$kind.avx2.hits" "$work/$kind.avx512.hits" \
            || echo "error: $kind $query: the avx2 and avx512 kernels' hits differ" >&2
        awk -v k="$kind" -v q="$query" -v a="$a" -v b="$b" -v e="$e" \
            'BEGIN {printf "%-8s %-9s %9.3f %9.3f %9.3f %8.2f %8.2f\n", k, q, a, b, e, a / e, b / e}'
    done
    i=$((i + 1))
done
awk '{la += log($3 / $5); lb += log($4 / $5); n++}
     END {printf "%-8s %-9s %9s %9s %9s %8.2f %8.2f\n", "geomean", "", "", "", "", exp(la / n), exp(lb / n)}' "$rows"
exec {EMB[1]}>&-
wait
