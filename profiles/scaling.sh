#!/usr/bin/env bash
# Cost as the scene grows: fields of 1, 4, 10 and 20 full Stanford dragons (profiles/field.py; the
# ten are scenes/dragon_field.p3f), each loaded, built and rendered at 640x360 by our BVH8 and by
# Embree, each in a process of its own for its peak memory (GNU time's maximum resident set), then
# both alternated frame by frame in one process for the frames' ratio (`bench --compare embree`).
# Writes profiles/scaling.json and docs/scaling.svg. Needs libembree-dev (the `embree` feature),
# python3 and GNU time. THREADS (default 2) and FRAMES (default 5) set the bench's.
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
root="$(dirname "$here")"
threads="${THREADS:-2}"
frames="${FRAMES:-5}"
for tool in python3 /usr/bin/time; do
    command -v "$tool" >/dev/null || {
        echo "scaling.sh: $tool not found (Debian: apt-get install python3 time)" >&2
        exit 1
    }
done
cd "$root"
cargo build --release --features embree --quiet
bin="$root/target/release/whitted"
tmp="$(mktemp -d)"
trap 'rm -rf "$tmp"' EXIT
rows="$tmp/rows"
: >"$rows"
for n in 1 4 10 20; do
    scene="$tmp/field_$n.p3f"
    python3 "$here/field.py" scene "$n" "$root/scenes/models/dragon_vrip.ply.gz" >"$scene"
    for accel in bvh8 embree; do
        /usr/bin/time -f %M -o "$tmp/rss" "$bin" bench "$scene" --accel "$accel" --frames "$frames" \
            --threads "$threads" --json >"$tmp/run.json"
        python3 - "$n" "$accel" "$tmp/run.json" "$tmp/rss" >>"$rows" <<'EOF'
import json, sys
n, accel, run, rss = sys.argv[1:]
r = json.load(open(run))
print(json.dumps({
    "dragons": int(n), "triangles": int(n) * 871414, "accel": "ours" if accel == "bvh8" else accel,
    "cpu": r["cpu"], "threads": r["threads"], "simd": r["simd"],
    "load_s": r["load_s"], "build_s": r["build_s"], "frame_ms": r["frame_ms_median"],
    "mrays_per_s": r["mrays_per_s"], "peak_gb": int(open(rss).read().split()[-1]) * 1024 / 1e9,
}))
EOF
    done
    "$bin" bench "$scene" --compare embree --frames "$frames" --threads "$threads" --json >"$tmp/compare.json"
    python3 - "$n" "$tmp/compare.json" >>"$rows" <<'EOF'
import json, sys
r = json.load(open(sys.argv[2]))
print(json.dumps({"dragons": int(sys.argv[1]), "triangles": int(sys.argv[1]) * 871414, "accel": "ratio",
                  "frame_ms": r["frame_ms_median"], "embree_frame_ms": r["compare"]["frame_ms_median"],
                  "speed_ratio": r["speed_ratio"]}))
EOF
done
python3 -c 'import json, sys; json.dump([json.loads(l) for l in open(sys.argv[1])], sys.stdout, indent=1)' \
    "$rows" >"$here/scaling.json"
python3 "$here/field.py" plot "$here/scaling.json" >"$root/docs/scaling.svg"
python3 "$here/field.py" table "$here/scaling.json"
