#!/usr/bin/env bash
# Binned SAH BVH2 (12 bins) of the 202k dragon collapsed into the BVH4, on one thread.
exec "$(dirname "$0")/callgrind.sh" sah-build build-sah
