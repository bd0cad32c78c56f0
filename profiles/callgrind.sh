#!/usr/bin/env bash
# callgrind.sh NAME LOOP...: runs each LOOP of the driver (profiles/hot_loops.rs) under callgrind and
# writes profiles/NAME.txt with the loop's instructions per ray (per triangle for the build) and the
# functions its instructions go to (exclusive counts). Instruction counts are repeatable (the same binary
# and inputs give the same total on a busy machine), unlike times; compare them across commits, not
# across toolchains. The per-loop scripts beside this one call it. FEATURES=... builds the driver with
# those cargo features; SIM=1 adds callgrind's cache and branch simulation (its model of this CPU's
# caches, read from cpuid, with no prefetcher) and prints D1 misses and mispredicted branches per unit.
# Valgrind instruments nothing until the driver has built its inputs (`--instr-atstart=no`), so that a
# big scene loads and builds at valgrind's plain speed; HOT_LOOPS_SCENE picks another scene (hot_loops.rs).
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
root="$(dirname "$here")"
name=$1
shift
for tool in valgrind callgrind_annotate; do
    command -v "$tool" >/dev/null || {
        echo "callgrind.sh: $tool not found (Debian: apt-get install valgrind)" >&2
        exit 1
    }
done
cd "$root"
cargo build --profile profiling --example hot_loops --quiet --features "hot-loops${FEATURES:+,$FEATURES}"
sim=()
[ "${SIM:-0}" = 1 ] && sim=(--cache-sim=yes --branch-sim=yes)
bin="$root/target/profiling/examples/hot_loops"
tmp="$(mktemp -d)"
trap 'rm -rf "$tmp"' EXIT
registry="${CARGO_HOME:-$HOME/.cargo}/registry/src/"
{
    echo "# profiles/$name.txt: written by profiles/$name.sh (callgrind, instructions executed)"
    echo "# $(rustc --version), $(valgrind --version), whitted $(git describe --always --dirty 2>/dev/null || echo unknown)"
    for loop in "$@"; do
        valgrind --tool=callgrind --callgrind-out-file="$tmp/$loop.out" --toggle-collect='*measured_*' --instr-atstart=no \
            "${sim[@]}" "$bin" "$loop" >"$tmp/$loop.count" 2>"$tmp/$loop.log" || {
            cat "$tmp/$loop.log" >&2
            exit 1
        }
        read -r unit n <"$tmp/$loop.count"
        callgrind_annotate --threshold=100 --show=Ir "$tmp/$loop.out" >"$tmp/$loop.txt" 2>/dev/null
        total=$(awk '/PROGRAM TOTALS/ { gsub(",", "", $1); print $1 }' "$tmp/$loop.txt")
        echo
        echo "## $loop: $n $unit, $total instructions, $((total / n)) per ${unit%s}"
        if [ "${#sim[@]}" -gt 0 ]; then
            # The caches valgrind modelled (sizes, associativity, line).
            echo "modelled: $(sed -n 's/^desc: \(.*cache:.*\)/\1/p' "$tmp/$loop.out" | paste -sd';' - | sed 's/;/; /g')"
            # The simulated events' totals, in the order of callgrind's `events:` line.
            callgrind_annotate --threshold=100 "$tmp/$loop.out" 2>/dev/null | awk -v n="$n" -v unit="${unit%s}" '
                /^Ir / { for (i = 1; i <= NF; i++) name[i] = $i }
                /PROGRAM TOTALS/ { k = 0; for (i = 1; i <= NF; i++) if ($i ~ /^[0-9,]+$/) { v = $i; gsub(",", "", v); val[name[++k]] = v }
                    printf "simulated, per %s: %.2f D1 read misses, %.2f LL read misses, %.2f of %.1f conditional branches mispredicted\n",
                        unit, val["D1mr"] / n, val["DLmr"] / n, val["Bcm"] / n, val["Bc"] / n }'
        fi
        # callgrind_annotate's lines ("count (share) file:function [object]"), paths made short.
        sed -n '/file:function/,$p' "$tmp/$loop.txt" | sed -e '1,2d' -e '/^$/d' -e '/^-----/,$d' \
            -e "s|$registry[^/]*/||g" -e "s|$root/||g" -e 's|/rustc/[0-9a-f]*/library/|std/|g' \
            -e 's| \[[^]]*\]$||' >"$tmp/$loop.lines"
        echo
        echo "by function (code inlined into a function counts as its own), exclusive:"
        awk -v total="$total" '{ n = $1; gsub(",", "", n); f = $0; sub(/^[^)]*\) +[^:]*:/, "", f); if (n + 0 > 0) sum[f] += n }
            END { for (f in sum) printf "%14d %5.1f%%  %s\n", sum[f], 100 * sum[f] / total, f }' \
            "$tmp/$loop.lines" | sort -rn | head -n 10
        echo
        echo "by source line's file (where the inlined instructions come from):"
        awk -v total="$total" '{ n = $1; gsub(",", "", n); f = $0; sub(/^[^)]*\) +/, "", f); sub(/:.*/, "", f); if (n + 0 > 0) sum[f] += n }
            END { for (f in sum) printf "%14d %5.1f%%  %s\n", sum[f], 100 * sum[f] / total, f }' \
            "$tmp/$loop.lines" | sort -rn | head -n 10
    done
} >"$tmp/out.txt"
mv "$tmp/out.txt" "$here/$name.txt"
cat "$here/$name.txt"
