#!/usr/bin/env bash
# BVH4 any hit, one ray at a time: a shadow ray to the light from each primary hit.
exec "$(dirname "$0")/callgrind.sh" any-hit any-shadow
