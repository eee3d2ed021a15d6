#!/usr/bin/env bash
# Regenerates the workbench screenshots shown in README.md. Most are rendered offscreen through
# OSMesa (`freqlab gui --headless`); one is a real GLFW window under Xvfb.
set -euo pipefail
cd "$(dirname "$0")/.."
bin=build/app/freqlab
[ -x "$bin" ] || { echo "build first: bash scripts/setup.sh" >&2; exit 1; }
# Every shot twice: 1280x800 at scale 1 in screenshots/, and 2560x1600 at --ui-scale 2 (a HiDPI
# screen) in screenshots/ui_scale_2/; a shot's own --size is its scale-1 size.
mkdir -p screenshots/ui_scale_2
shot() {
  out=$1; shift
  local size=1280x800 args=()
  while [ $# -gt 0 ]; do
    if [ "$1" = --size ]; then size=$2; shift 2; else args+=("$1"); shift; fi
  done
  local w=${size%x*} h=${size#*x}
  env -u DISPLAY "$bin" gui "${args[@]}" --size "$size" --headless --screenshot "screenshots/$out"
  env -u DISPLAY "$bin" gui "${args[@]}" --size "$((2 * w))x$((2 * h))" --ui-scale 2 --headless \
      --screenshot "screenshots/ui_scale_2/$out"
}
shot viewport_color.png scenes/rotor.json --method mis --set mis.spp=32 --frame 0
shot overlay_colorbar.png scenes/rotor.json --method mis --set mis.spp=32 --frame 0 --overlay variance
shot inspector.png builtin:default --method mis --frame 0 --overlay object --inspect 320,250
shot timeline_stats.png builtin:default --method mis --set mis.spp=8 --set frame.width=320 \
     --set frame.height=180 --warm-from 0 --frame 23
xvfb-run -a -s "-screen 0 1280x800x24" "$bin" gui scenes/creatures.json --method mis \
     --set mis.spp=16 --overlay normal --size 1280x800 --screenshot screenshots/window_creatures_normals.png
xvfb-run -a -s "-screen 0 2560x1600x24" "$bin" gui scenes/creatures.json --method mis \
     --set mis.spp=16 --overlay normal --size 2560x1600 --ui-scale 2 \
     --screenshot screenshots/ui_scale_2/window_creatures_normals.png
shot compare_split.png scenes/rotor.json --method mis --set mis.spp=4 --set reference.spp=256 \
     --set frame.width=480 --set frame.height=270 --frame 0 --compare
shot tables_panel.png builtin:default --method gbuffer --frame 0 --tables
shot tables_panel_area.png builtin:default --method gbuffer --frame 0 --tables --tables-emitter area
shot points_inspector.png scenes/rotor.json --method points --frame 3 --overlay N_omega --inspect 330,250 \
    
shot env_bandwidth.png scenes/rotor.json --method gbuffer --frame 0 --env-bandwidth --overlay "B_L r=22.5deg"
shot sparse_density.png scenes/rotor.json --method sparse --frame 0 --overlay density
shot sparse_sampled.png scenes/rotor.json --method sparse --frame 0 --overlay sampled
shot sparse_inspector.png scenes/rotor.json --method sparse --frame 0 --overlay sampled --inspect 300,280 \
    
shot cache_decisions.png scenes/rotor.json --method cache --warm-from 0 --frame 6 --overlay cache_decisions \
     --set frame.width=480 --set frame.height=270 --inspect 230,200
# The cache's "why" for a pixel: the inspector's trace tab (each entry's tests and numbers).
shot cache_trace.png scenes/rotor.json --method cache --warm-from 0 --frame 6 --overlay cache_decisions \
     --set frame.width=480 --set frame.height=270 --inspect 230,200 --inspect-trace
shot cache_decision_layer.png scenes/truck.json --method cache --warm-from 0 --frame 12 --overlay decision \
     --set frame.width=480 --set frame.height=270
# Method B: the lightmapped preview of a bake and the in-scattered light alone.
shot bake_cornell_impulse.png scenes/cornell_fog.json --method impulse --set bake.spp=256 \
     --set frame.width=480 --set frame.height=360
shot bake_smoke_inscatter.png scenes/smoke_room.json --method impulse --set bake.spp=128 \
     --set frame.width=480 --set frame.height=360 --overlay lm_inscatter --inspect 240,200
shot bake_zh_lobes.png scenes/cornell_fog.json --method impulse --set bake.spp=128 \
     --set frame.width=480 --set frame.height=360 --inspect 150,335
# The Method B tables panel in a bake session, its sliders on the scene's fog.
shot bake_tables_panel.png scenes/cornell_fog.json --method impulse --set bake.spp=64 \
     --set frame.width=480 --set frame.height=360 --tables
# The production scene (issue "Method B, part 4"): its lightmapped preview, impulse | VPT.
shot bake_valley_split_vpt.png scenes/valley.json --method impulse --set bake.quality=low \
     --set bake.texel_density=1 --set frame.width=640 --set frame.height=400 --compare
# Where impulse's Monte Carlo terms rest on few texels: the texel filter's window (texel_mc_window)
# over the same preview (walls and the ground under houses: small; open ground: the whole 7 x 7).
# With the texels' own terms: the preset's texels read the vertex correction field instead.
shot bake_valley_mc_window.png scenes/valley.json --method impulse --set bake.quality=low \
     --set bake.texel_terms=own \
     --set bake.texel_density=1 --set frame.width=640 --set frame.height=400 \
     --overlay texel_mc_window --inspect 560,330
# Its time-error plot: bench --study bake at 1 texel/unit (the plot is the study's own PNG).
study=$(mktemp -d)
"$bin" bench scenes/valley.json --study bake --set bake.quality=low --set bake.texel_density=1 \
     --reference-spp 256 --max-spp 64 --out "$study" > /dev/null
cp "$study/bench_bake_time_error.png" screenshots/bake_time_error_valley.png
rm -rf "$study"
shot bake_split_vpt.png scenes/cornell_fog.json --method impulse --set bake.spp=64 \
     --set frame.width=480 --set frame.height=360 --compare
# Method B, light scattered into shadows: an umbra texel's trace (the lit medium's visibility and
# both contributions of the occluded connection) and the analytic scene, impulse | VPT.
shot bake_shadow_trace.png scenes/analytic/haze_occluder.json --method impulse --set bake.spp=256 \
     --set bake.texel_density=8 --set bake.probes_x=0 --set frame.width=480 --set frame.height=360 \
     --inspect 220,196 --inspect-trace
shot bake_haze_occluder_split.png scenes/analytic/haze_occluder.json --method impulse \
     --set bake.spp=256 --set bake.texel_density=8 --set bake.probes_x=0 --set frame.width=480 \
     --set frame.height=360 --compare
# The same bake with its Monte Carlo terms unfiltered (bake.texel_mc_radius=0): 1 path in 50 runs
# them, so at 256 spp each texel has ~5; the default filter averages them over its neighbours.
shot bake_mc_unfiltered.png scenes/analytic/haze_occluder.json --method impulse \
     --set bake.spp=256 --set bake.texel_density=8 --set bake.probes_x=0 --set bake.texel_mc_radius=0 \
     --set frame.width=480 --set frame.height=360
# A paper figure of a categorical layer: what Export > Figure writes in the workbench (the same
# pixels, checked by hand under Xvfb in session 20), from the command line: legend swatches in
# the layer's own palette (white reused, orange temporal, blue spatial).
fig_dir=$(mktemp -d)
"$bin" render scenes/rotor.json --method cache --frames 0:3 --size 640x360 --quiet --out "$fig_dir"
"$bin" figure "$fig_dir/frame_0002.exr" --layer cache_decisions \
     --title "rotor, frame 2, cache_decisions" --out screenshots/figure_cache_decisions.png
rm -rf "$fig_dir"
# window_checkpoint_jump.png is a journey in a real window (session 23, Xvfb + xdotool, by hand):
# `freqlab gui scenes/rotor.json --method cache --set frame.width=320 --set frame.height=180
# --set cache.checkpoint_every=5`, Right arrow 11 times (checkpoints before 5 and 10 in the run
# store), quit, start it again (to 13 first, then quit again) and click frame 23 on the
# timeline: the shot is taken while it renders frame 16 on the way, from the checkpoint before
# 10, the viewport holding frame 16's first image (ticks: green recorded, orange pending, white
# shown; session 26: the way's ETA, the cache panel on frame 15, and the points of frames 10-13
# recalled from the run store's shading memo, written by the session that rendered them).
# window_first_start.png / window_first_start_decisions.png: `freqlab` with no argument in a
# real window under Xvfb (session 23, by hand): method A's cache on the built-in scene, playing,
# with the hint line; then the D key (cache decisions over the colour).
# window_ab_split.png / window_first_image.png: A/B of two recorded runs in a real window under
# Xvfb (session 24, by hand): `freqlab gui scenes/rotor.json --method cache --frame 4 --set
# frame.width=640 --set frame.height=360` (frames 0-4 recorded; opened again they come from the
# run store at once), Settings scrolled down, "A/B runs" > "Keep this run as A", ctrl-click
# q_eps_x and type 0.002: window_first_image.png is taken while B renders frame 0 on the way to 4
# (its first image from the initial grid, B left of the split, A's frame 0 right);
# window_ab_split.png when frame 4 is rendered (metrics B against A, A's time_ms under B's).
