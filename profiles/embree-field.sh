#!/usr/bin/env bash
# embree.sh's comparison on the field of ten full dragons (scenes/dragon_field.p3f, 8.7 M triangles at
# its 640x360): a tree whose nodes and leaves (about 570 MB) are far past the last-level cache, so that
# the simulated last-level misses (DRAM reads) show where the diffuse and shadow rays' time goes.
# Valgrind loads and builds the scene uninstrumented (a few minutes each loop); needs the `embree` feature.
HOT_LOOPS_SCENE=scenes/dragon_field.p3f FEATURES=embree SIM=1 exec "$(dirname "$0")/callgrind.sh" \
    embree-field closest-diffuse-bvh8 closest-diffuse-embree any-shadow-bvh8 any-shadow-embree \
    packet-diffuse-bvh8 packet-diffuse-embree
