#!/usr/bin/env bash
# BVH4 closest hit, one ray at a time: the 57,600 primary rays and the diffuse bounce of each hit.
exec "$(dirname "$0")/callgrind.sh" closest-hit closest-primary closest-diffuse
