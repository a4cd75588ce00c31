#!/usr/bin/env bash
# Runs a command under a private virtual X server (Debian's ParaView renders
# through GLX): Xvfb picks a free display and names it once it accepts
# connections (-displayfd), and does not reset when its last client leaves
# (-noreset: ParaView probes OpenGL on a connection it closes before opening
# its own, which a resetting server refused one run in three, "bad X server
# connection", with xvfb-run too).
set -euo pipefail
dir="$(mktemp -d)"
Xvfb -displayfd 3 -screen 0 1024x768x24 -nolisten tcp -noreset 3>"$dir/display" 2>"$dir/log" &
server=$!
trap 'kill "$server" 2>/dev/null || true; wait "$server" 2>/dev/null || true; rm -rf "$dir"' EXIT
for _ in $(seq 100); do
  [ -s "$dir/display" ] && break
  sleep 0.1
done
[ -s "$dir/display" ] || { echo "with_xvfb.sh: Xvfb did not start: $(cat "$dir/log")" >&2; exit 1; }
DISPLAY=":$(cat "$dir/display")" "$@"
