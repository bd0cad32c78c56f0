#!/usr/bin/env bash
# BVH8 single rays (AVX2 slab test where the CPU has it): closest hit on the primary rays and the diffuse
# bounces, any hit on the shadow rays; the same workload as closest-hit.sh and any-hit.sh.
exec "$(dirname "$0")/callgrind.sh" bvh8 closest-primary-bvh8 closest-diffuse-bvh8 any-shadow-bvh8
