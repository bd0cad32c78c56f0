#!/usr/bin/env bash
# The packet kernel, 8 consecutive rays a packet: the BVH4's on the primary rays (closest hit) and the
# shadow rays (any hit), and the BVH8's (the default accelerator's on AVX2 CPUs) on those and the diffuse
# bounces (closest hit), which packets leave incoherent.
exec "$(dirname "$0")/callgrind.sh" packets packet-primary packet-shadow \
    packet-primary-bvh8 packet-shadow-bvh8 packet-diffuse-bvh8
