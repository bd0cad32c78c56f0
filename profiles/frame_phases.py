"""Splits a frame's callgrind profile by phase (profiles/frame.sh).

Reads `callgrind_annotate --inclusive=yes --tree=caller` output and the driver's ray counts, and prints
each phase's inclusive instructions, its share of the frame and its instructions per ray of its kind.
A phase is the inclusive cost of the functions it runs in: the accelerator's verbs are never
inlined into the integrator (the packet verbs reach their AVX2 kernel through a `#[target_feature]`
function, the single-ray closest-hit verbs are `#[inline(never)]`), so traversal is measured exactly, and its ray kind is
told by the caller: the integrator's lanes walk (`trace_lanes`) at its first level traces the camera rays, its
recursive levels (callgrind's `'2`) the reflected and refracted ones. Names are Rust's v0 mangling
(frame.sh builds with it): generic functions carry their arguments, so that the shading's bodies,
each run on its lanes through `Lanes::call` (`with_avx2::<_, ...::{closure#0}>`), are told apart.
"""

import re
import sys

LINE = re.compile(r"^\s*([\d,]+)\s+\(\s*[\d.]+%\)\s+(<|\*)?\s*(\S.*)$")


def name(text):
    """The function of a `file:function [object] (Nx)` field."""
    text = re.sub(r" \[[^]]*\]$", "", text.strip())
    text = re.sub(r" \([\d,]+x\)$", "", text)
    return text.split(":", 1)[1] if ":" in text else text


def base(f):
    """A function's path without its trailing generic arguments (`f::<A, B>` is `f`)."""
    f = re.sub(r"'\d+$", "", f)
    f = re.sub(r"^<([^<>]*)>::", r"\1::", f)
    while f.endswith(">") and "::<" in f:
        depth, i = 0, len(f) - 1
        while i >= 0:
            depth += {">": 1, "<": -1}.get(f[i], 0)
            if depth == 0:
                break
            i -= 1
        if f[i - 2 : i] != "::":
            break
        f = f[: i - 2]
    return f


def recursive(f):
    """Whether `f` is a recursive call's level (callgrind's `'2` and deeper)."""
    return re.search(r"'\d+$", f) is not None


def blocks(path):
    """Each function's inclusive count and its callers' counts, from the entry with the largest count
    (callgrind_annotate lists a function once per source file its lines come from)."""
    functions, callers, current = {}, [], []
    total = 0
    for line in open(path, encoding="utf-8", errors="replace"):
        if "PROGRAM TOTALS" in line:
            total = int(line.split()[0].replace(",", ""))
            continue
        m = LINE.match(line)
        if not m:
            current = []
            continue
        count, mark, rest = int(m.group(1).replace(",", "")), m.group(2), m.group(3)
        if mark == "<":
            current.append((name(rest), count))
        elif mark == "*":
            f = name(rest)
            if count > functions.get(f, (0, []))[0]:
                functions[f] = (count, current)
            current = []
    return total, functions


def main():
    total, functions = blocks(sys.argv[1])
    counts = {}
    for line in open(sys.argv[2]):
        words = line.split()
        if words and words[0] == "kinds":
            counts = {words[i]: int(words[i + 1]) for i in range(1, len(words), 2)}

    def verb(f, suffix):
        # A verb is `Accel::<verb>` or, written once for both tallies, `Verbs<...>::<verb>`.
        name = suffix.removeprefix("Accel")
        f = base(f)
        return f.endswith(suffix) or ("Verbs<" in f and f.endswith(">" + name))

    def inclusive(suffix):
        return sum(c for f, (c, _) in functions.items() if not recursive(f) and verb(f, suffix))

    def phase(name):
        # A body run on the packet's lanes through `Lanes::call`: `with_avx2::<_, ...name...::{closure#0}>`.
        return sum(
            c
            for f, (c, _) in functions.items()
            if not recursive(f) and "with_avx2" in f and f"::{name}" in f.split(", ", 1)[-1]
        )

    def called_by(suffix, caller_test):
        return sum(
            n
            for f, (_, callers) in functions.items()
            if verb(f, suffix)
            for caller, n in callers
            if caller_test(caller)
        )

    first_level = lambda c: "trace_lanes" in c and not recursive(c)  # noqa: E731
    deeper = lambda c: "trace_lanes" in c and recursive(c)  # noqa: E731
    phases = [
        ("camera rays and their samples (camera_packet)", inclusive("::camera_packet"), "primary"),
        ("sample patterns (PixelPattern::fill, spp > 1 only)", inclusive("PixelPattern::fill"), "primary"),
        ("traversal, camera rays (packets)", called_by("Accel::intersect_packet", first_level), "primary"),
        (
            "traversal, shadow rays (packets and single)",
            inclusive("Accel::occluded_packet") + inclusive("Accel::occluded"),
            "shadow",
        ),
        (
            "traversal, reflected and refracted rays (packets and single)",
            called_by("Accel::intersect_packet", deeper) + inclusive("Accel::intersect"),
            "secondary",
        ),
        (
            "hit points: position, normals (HitLanes::of_hits)",
            phase("of_hits"),
            "all",
        ),
        (
            "shading in lanes: shadow rays' set-up, Blinn-Phong (local_lanes)",
            phase("local_lanes")
            - called_by("Accel::occluded_packet", lambda c: "local_lanes" in c)
            - called_by("Accel::occluded", lambda c: "local_lanes" in c),
            "all",
        ),
    ]
    rays = sum(counts.values())
    measured = sum(n for _, n, _ in phases)
    phases.append(("shading, the integrator, tiles and film (the rest)", total - measured, "all"))
    print()
    print(
        f"## frame: {rays} rays ({counts.get('primary', 0)} camera, {counts.get('shadow', 0)} shadow, "
        f"{counts.get('secondary', 0)} reflected and refracted), {total} instructions, "
        f"{total // max(rays, 1)} per ray"
    )
    print()
    print(f"{'phase':<62} {'instructions':>13} {'share':>6} {'per ray':>8}  (of)")
    for label, n, kind in phases:
        of = rays if kind == "all" else counts.get(kind, 0)
        print(f"{label:<62} {n:>13,} {100 * n / total:>5.1f}% {n / max(of, 1):>8.0f}  ({kind})")


main()
