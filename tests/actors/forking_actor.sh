#!/bin/sh
# An actor that leaves children behind: one in its process group, one that escapes it with setsid, both living far
# longer than any farm; then it becomes the Python tint actor. The farm must end them all.
sleep 307 &
setsid sleep 308 &
exec /usr/bin/python3 "$(dirname "$0")/../../examples/plugin-python/tint.py" "$@"
