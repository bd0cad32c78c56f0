#!/usr/bin/env bash
# The BVH4 of the 202k dragon as the accelerator builds it (binned SAH with 12 bins and the wide BVHs'
# four-triangle leaf blocks, collapsed), on one thread.
exec "$(dirname "$0")/callgrind.sh" sah-build build-sah
