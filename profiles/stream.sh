#!/usr/bin/env bash
# A whole frame of the course's dragon.p3f at 320x180 on the BVH8, one thread, with the packet kernel
# (`frame`, what `whitted render` runs) and with the stream kernel (`frame-stream`, `--kernel stream`):
# each frame's instructions, and how many of them went into each of the accelerator's verbs (inclusive
# counts of Accel::intersect, occluded, their _packet and _stream forms) and into the rest (camera
# rays, shading, the drivers' bookkeeping). Writes profiles/stream.txt with the wall-clock figures
# below it kept. Needs valgrind.
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
root="$(dirname "$here")"
command -v valgrind >/dev/null && command -v callgrind_annotate >/dev/null || {
    echo "stream.sh: valgrind not found (Debian: apt-get install valgrind)" >&2
    exit 1
}
cd "$root"
cargo build --profile profiling --example hot_loops --features hot-loops --quiet
tmp="$(mktemp -d)"
trap 'rm -rf "$tmp"' EXIT
{
    echo "# profiles/stream.txt: written by profiles/stream.sh (callgrind, instructions executed)"
    echo "# $(rustc --version), $(valgrind --version), whitted $(git describe --always --dirty 2>/dev/null || echo unknown)"
    echo
    for loop in frame frame-stream; do
        valgrind --tool=callgrind --callgrind-out-file="$tmp/$loop.out" --toggle-collect='*measured_*' \
            target/profiling/examples/hot_loops "$loop" >"$tmp/$loop.counts" 2>"$tmp/$loop.log" || {
            cat "$tmp/$loop.log" >&2
            exit 1
        }
        total=$(sed -n 's/.*Collected : \([0-9]*\).*/\1/p' "$tmp/$loop.log")
        rays=$(sed -n 's/^rays \([0-9]*\)$/\1/p' "$tmp/$loop.counts")
        echo "## $loop: $rays rays, $total instructions, $((total / rays)) per ray"
        callgrind_annotate --inclusive=yes "$tmp/$loop.out" 2>/dev/null >"$tmp/$loop.txt"
        traversal=0
        for verb in intersect occluded intersect_packet occluded_packet intersect_stream occluded_stream; do
            # The verb as `Accel::verb` or, where that is inlined, `Verbs<...>::verb`: the larger
            # inclusive count of the two (the outer call).
            n=$(grep -E "^ *[0-9,]+ .*whitted::accel::(Accel|Verbs<[^>]*>)::${verb}( \[[^]]*\])?\$" "$tmp/$loop.txt" |
                awk '{gsub(",", "", $1); print $1}' | sort -n | tail -1 || true)
            n=${n:-0}
            traversal=$((traversal + n))
            if [ "$n" -gt 0 ]; then printf '  %-18s %12d\n' "$verb" "$n"; fi
        done
        printf '  %-18s %12d\n' "all verbs" "$traversal"
        printf '  %-18s %12d\n' "the rest" "$((total - traversal))"
        echo
    done
} >"$tmp/out.txt"
# The hand-written notes after the recorded figures stay.
if [ -f "$here/stream.txt" ]; then
    sed -n '/^## Notes/,$p' "$here/stream.txt" >>"$tmp/out.txt"
fi
mv "$tmp/out.txt" "$here/stream.txt"
cat "$here/stream.txt"
