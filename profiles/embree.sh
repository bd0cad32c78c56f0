#!/usr/bin/env bash
# Embree 3's single rays and 8-wide packets beside our BVH8's on the same rays (closest hit on the
# primary rays and the diffuse bounces, any hit on the shadow rays), with callgrind's cache and branch
# simulation: where the kernels differ besides the instruction count. Needs the `embree` feature's system library
# (Debian: apt-get install libembree-dev). Under valgrind both dispatch to their AVX2 code.
FEATURES=embree SIM=1 exec "$(dirname "$0")/callgrind.sh" embree \
    closest-primary-bvh8 closest-primary-embree closest-diffuse-bvh8 closest-diffuse-embree \
    any-shadow-bvh8 any-shadow-embree packet-primary-bvh8 packet-primary-embree \
    packet-shadow-bvh8 packet-shadow-embree packet-diffuse-bvh8 packet-diffuse-embree
