#!/usr/bin/env bash
# Regenerates the workbench screenshots shown in README.md: a real GLFW window under Xvfb,
# read back from its framebuffer by `freqlab gui --screenshot`.
set -euo pipefail
cd "$(dirname "$0")/.."
bin=build/app/freqlab
[ -x "$bin" ] || { echo "build first: bash scripts/setup.sh" >&2; exit 1; }
run() { xvfb-run -a -s "-screen 0 1280x800x24" "$bin" gui "$@"; }
run builtin:default --frame 0 --screenshot screenshots/workbench_color.png
run builtin:default --frame 24 --overlay normal --screenshot screenshots/workbench_normal_layer.png
run builtin:default --frame 24 --overlay object --screenshot screenshots/workbench_object_layer.png
run scenes/showcase.json --frame 0 --screenshot screenshots/workbench_showcase.png
