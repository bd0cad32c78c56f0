#!/usr/bin/env bash
# BVH4 packet kernel, 8 consecutive rays a packet: the primary rays (closest hit) and the shadow rays (any hit).
exec "$(dirname "$0")/callgrind.sh" packets packet-primary packet-shadow
