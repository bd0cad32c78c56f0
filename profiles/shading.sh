#!/usr/bin/env bash
# A whole frame of the course's dragon.p3f at 320x180 (Whitted: shadows, reflection, refraction), one thread.
exec "$(dirname "$0")/callgrind.sh" shading shade
