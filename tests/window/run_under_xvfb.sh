#!/usr/bin/env bash
# Runs a window test on a virtual X server; exits 77 (ctest: skipped) when Xvfb is missing.
if ! command -v xvfb-run >/dev/null 2>&1; then
  echo "SKIPPED: xvfb-run is not installed (apt-get install xvfb xauth); the window test needs an X server"
  exit 77
fi
exec xvfb-run -a -s "-screen 0 1280x800x24" "$@"
