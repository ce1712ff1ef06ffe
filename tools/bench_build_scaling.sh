#!/usr/bin/env bash
# The load and the BVH build of the 13.9M-triangle dragon over threads:
# for 1, 2, 4, 8 and 16 threads, each step of the load and of the build
# (`strata render --stats`'s time.load_steps and time.build_steps) for the
# fastest and the medium presets, and the speedup over one thread.
#
#   tools/bench_build_scaling.sh [STRATA] [ASSETS_DIR]
#
# STRATA is the strata binary (default target/release/strata), ASSETS_DIR
# holds dragon.ply (default assets/); dragon-sub2.ply is made beside it by
# `python3 tools/fetch-assets --subdivide 2` (numpy; offline, from
# dragon.ply) unless it is there. Each setting runs ROUNDS times (default
# 3), median shown, alternating over the settings; rounds stop starting
# once DEADLINE_S seconds (default 150) have passed. Needs bash, python3
# (for the JSON) and the binary; no network. About 2 minutes on 16 cores.
set -euo pipefail

root=$(cd "$(dirname "$0")/.." && pwd)
strata=${1:-$root/target/release/strata}
assets=${2:-$root/assets}
rounds=${ROUNDS:-3}
deadline=${DEADLINE_S:-150}
threads_list=${THREADS:-"1 2 4 8 16"}
presets=${PRESETS:-"fastest medium"}

[ -x "$strata" ] || { echo "error: $strata is not an executable strata binary" >&2; exit 2; }
[ -f "$assets/dragon.ply" ] || { echo "error: $assets/dragon.ply is missing" >&2; exit 2; }
mesh=$assets/dragon-sub2.ply
if [ ! -f "$mesh" ]; then
    made=$SECONDS
    python3 "$root/tools/fetch-assets" --only dragon --subdivide 2 --dest "$assets" >/dev/null
    echo "made $mesh in $((SECONDS - made)) s"
fi

out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
start=$SECONDS
for round in $(seq 1 "$rounds"); do
    if [ "$round" -gt 1 ] && [ $((SECONDS - start)) -ge "$deadline" ]; then
        echo "stopped after $((round - 1)) rounds: past ${deadline} s"
        break
    fi
    for preset in $presets; do
        for t in $threads_list; do
            "$strata" render "$mesh" --width 320 --height 240 --spp 1 --threads "$t" \
                --bvh-quality "$preset" --quiet --stats "$out/$preset-$t-$round.json" \
                -o "$out/image.png" 2>/dev/null
        done
    done
done

model=$(lscpu | sed -n 's/^Model name:[[:space:]]*//p' | head -1)
echo "CPU: $model, $(nproc) CPUs; strata render dragon-sub2.ply --spp 1 320x240; seconds, median of rounds"
python3 - "$out" "$presets" "$threads_list" <<'EOF'
import glob, json, os, statistics, sys

out, presets, threads = sys.argv[1], sys.argv[2].split(), [int(t) for t in sys.argv[3].split()]

def med(xs):
    return statistics.median(xs) if xs else float("nan")

for preset in presets:
    runs = {t: [json.load(open(f)) for f in sorted(glob.glob(os.path.join(out, f"{preset}-{t}-*.json")))]
            for t in threads}
    runs = {t: r for t, r in runs.items() if r}
    if not runs:
        continue
    first = next(iter(runs.values()))[0]
    load_steps = list(first["time"]["load_steps"])
    build_steps = list(first["time"]["build_steps"])
    cols = ["load"] + load_steps + ["build"] + build_steps
    short = {"reinsertion": "reins", "collapse": "collap", "clusters": "clust", "compile": "compil"}
    print(f"\n{preset} ({first['triangles'] / 1e6:.2f} M triangles, {len(first and runs[min(runs)])} rounds)")
    print("thr " + " ".join(f"{short.get(c, c)[:6]:>6}" for c in cols) + "  total  x_load x_build x_total")
    base = None
    for t, rs in runs.items():
        row = {"load": med([r["time"]["load_s"] for r in rs]), "build": med([r["time"]["bvh_build_s"] for r in rs])}
        for c in load_steps:
            row[c] = med([r["time"]["load_steps"].get(c, 0.0) for r in rs])
        for c in build_steps:
            row[c] = med([r["time"]["build_steps"].get(c, 0.0) for r in rs])
        total = row["load"] + row["build"]
        if base is None:
            base = (row["load"], row["build"], total)
        speed = [b / max(x, 1e-9) for b, x in zip(base, (row["load"], row["build"], total))]
        print(f"{t:>3} " + " ".join(f"{row[c]:6.3f}" for c in cols)
              + f" {total:6.2f} " + " ".join(f"{s:6.2f}x" for s in speed))
EOF
