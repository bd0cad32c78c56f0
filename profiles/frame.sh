#!/usr/bin/env bash
# A whole frame of the course's dragon.p3f at 320x180 with the default accelerator (what `whitted
# render` runs: the BVH8 and packets on AVX2 CPUs), one thread, split by phase: the inclusive
# instructions of the functions each phase runs in (traversal by ray kind through the caller of the
# accelerator's verbs). Writes profiles/frame.txt. Needs valgrind and python3.
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
root="$(dirname "$here")"
for tool in valgrind callgrind_annotate python3; do
    command -v "$tool" >/dev/null || {
        echo "frame.sh: $tool not found (Debian: apt-get install valgrind python3)" >&2
        exit 1
    }
done
cd "$root"
# Rust's v0 symbol names keep generic arguments, which tell the shading's lanes bodies apart
# (frame_phases.py); built apart from the other scripts' binary, so that neither rebuilds the other's.
export RUSTFLAGS="-C symbol-mangling-version=v0" CARGO_TARGET_DIR="$root/target/frame"
cargo build --profile profiling --example hot_loops --features hot-loops --quiet
tmp="$(mktemp -d)"
trap 'rm -rf "$tmp"' EXIT
valgrind --tool=callgrind --callgrind-out-file="$tmp/frame.out" --toggle-collect='*measured_*' \
    "$CARGO_TARGET_DIR"/profiling/examples/hot_loops frame >"$tmp/counts" 2>"$tmp/log" || {
    cat "$tmp/log" >&2
    exit 1
}
callgrind_annotate --inclusive=yes --tree=caller "$tmp/frame.out" >"$tmp/tree.txt" 2>/dev/null
{
    echo "# profiles/frame.txt: written by profiles/frame.sh (callgrind, instructions executed)"
    echo "# $(rustc --version), $(valgrind --version), whitted $(git describe --always --dirty 2>/dev/null || echo unknown)"
    python3 "$here/frame_phases.py" "$tmp/tree.txt" "$tmp/counts"
} >"$tmp/out.txt"
mv "$tmp/out.txt" "$here/frame.txt"
cat "$here/frame.txt"
