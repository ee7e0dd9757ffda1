#!/usr/bin/env bash
# lightfarm against Cycles on the same glTF file (issue: scenes as artists make them): Blender's material-ball grid
# (../shared/scenes/gltf/balls.glb) under an HDRI and the file's sun, 320x180, 2 cores. Cycles imports the file with
# Blender's own glTF importer (Principled BSDFs; cycles_balls.py); lightfarm renders examples/material_balls.lua
# (its network: direct + glossy over path-traced bounces). Prints
#   1. per-ball means (inner discs; balls_peer.py) of Cycles with Principled GGX, Cycles with multiscatter GGX and
#      lightfarm, at 256 spp, two seeds each averaged; and the same with every material made Lambert on both sides
#      (the light transport alone, without the material models);
#   2. quality per time: each renderer's noise from a pair of seeds at 64 and 256 spp (no reference), its seconds
#      (Cycles: its render call; lightfarm: the whole run), and the time lightfarm takes to reach Cycles' 256-spp
#      noise as a share of Cycles' time, for the example's network and for its path tracer (lighting=pathtrace);
#   3. with `glass` as the fourth argument, also the front row as rough glass and everything else Lambert on both
#      sides (GLASS, glass=1) at 1024 spp: the glass model alone.
# Needs `blender` (Debian's 3.4) and a built lightfarm. About three minutes.
#
#   bench/peer/compare_balls.sh [LIGHTFARM] [HDRI] [sun|nosun] [glass]   e.g. bench/peer/compare_balls.sh build/lightfarm courtyard
# nosun takes the file's sun out on both sides: the HDRI alone, without the sun's sub-degree glints, whose rare
# fireflies make the noise of a seed pair a lottery.
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
lightfarm=${1:-$here/../../build/lightfarm}
hdri=${2:-courtyard}
sun=${3:-sun}
glass=${4:-}
lf_sun=1
[[ $sun == nosun ]] && lf_sun=0
map=$here/../../../shared/scenes/gltf/hdri/$hdri.exr
command -v blender >/dev/null || { echo "compare_balls.sh: needs blender (apt-get install blender)" >&2; exit 2; }
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
size=(--set width=320 --set height=180)
declare -A secs
cycles() {  # OUT SPP SEED MODEL
  blender -b -P "$here/cycles_balls.py" -- "$1" "$2" 320 180 "$3" "$map" "$4" "$sun" 2>/dev/null | awk '/RENDER_SECONDS/ {print $2}'
}
# lf: the example's network; pt: the same example's path tracer (--set lighting=pathtrace).
for spp in 64 256; do
  for seed in 3 4; do
    for kind in lf pt; do
      lighting=network
      [[ $kind == pt ]] && lighting=pathtrace
      t0=$EPOCHREALTIME
      "$lightfarm" run "$here/../../examples/material_balls.lua" "${size[@]}" --set spp=$spp --set seed=$seed \
        --set hdri=$hdri --set sun=$lf_sun --set lighting=$lighting --output "$out/${kind}_${spp}_$seed.exr" --quiet 2>/dev/null
      secs[${kind}_${spp}_$seed]=$(python3 -c "print($EPOCHREALTIME - $t0)")
    done
    secs[cy_${spp}_$seed]=$(cycles "$out/cy_${spp}_$seed.exr" $spp $seed GGX)
  done
done
cycles "$out/cy_multi_3.exr" 256 3 MULTI_GGX >/dev/null
cycles "$out/cy_multi_4.exr" 256 4 MULTI_GGX >/dev/null
cycles "$out/cy_lambert_3.exr" 256 3 LAMBERT >/dev/null
"$lightfarm" run "$here/lightfarm_balls_lambert.lua" --set hdri=$hdri --set sun=$lf_sun --set seed=3 --output "$out/lf_lambert_3.exr" --quiet 2>/dev/null
# Two seeds averaged: 512 samples' worth for the means.
blender -b --python-expr "
import bpy, numpy, sys
d = '$out'
for name in ('cy_256', 'cy_multi', 'lf_256'):
    imgs = [bpy.data.images.load(d + '/%s_%d.exr' % (name, s)) for s in (3, 4)]
    px = []
    for im in imgs:
        a = numpy.empty(len(im.pixels), dtype=numpy.float32); im.pixels.foreach_get(a); px.append(a)
    out = imgs[0].copy(); out.pixels.foreach_set((px[0] + px[1]) / 2)
    out.filepath_raw = d + '/%s_mean.exr' % name; out.file_format = 'OPEN_EXR'; out.save()
" >/dev/null 2>&1
json=$out/cy_256_3.exr.balls.json
echo "lightfarm against Cycles on balls.glb under $hdri.exr ($sun); 320x180, 2 cores"
echo "1. means over each ball's inner disc and the floor (columns: Cycles Principled GGX, Cycles multiscatter GGX, lightfarm)"
blender -b -P "$here/balls_peer.py" -- "$json" means "$out/cy_256_mean.exr" "$out/cy_multi_mean.exr" "$out/lf_256_mean.exr" 2>/dev/null | grep '^MEAN'
echo "   every material Lambert (columns: Cycles, lightfarm)"
blender -b -P "$here/balls_peer.py" -- "$json" means "$out/cy_lambert_3.exr" "$out/lf_lambert_3.exr" 2>/dev/null | grep '^MEAN'
noise=$(blender -b -P "$here/balls_peer.py" -- "$json" noise \
          "$out/lf_64_3.exr" "$out/lf_64_4.exr" "$out/lf_256_3.exr" "$out/lf_256_4.exr" \
          "$out/cy_64_3.exr" "$out/cy_64_4.exr" "$out/cy_256_3.exr" "$out/cy_256_4.exr" \
          "$out/pt_64_3.exr" "$out/pt_64_4.exr" "$out/pt_256_3.exr" "$out/pt_256_4.exr" 2>/dev/null | awk '/^NOISE/ {print $4}')
read -r lf64 lf256 cy64 cy256 pt64 pt256 <<<"$(echo $noise)"
echo "2. quality per time (noise from seed pairs over the balls' discs and the floor); lf: the network"
python3 "$here/quality_per_time.py" "$lf64" "$lf256" "$cy64" "$cy256" "${secs[lf_64_3]}" "${secs[lf_64_4]}" \
  "${secs[lf_256_3]}" "${secs[lf_256_4]}" "${secs[cy_64_3]}" "${secs[cy_64_4]}" "${secs[cy_256_3]}" "${secs[cy_256_4]}"
echo "   the same with lightfarm's path tracer (lighting=pathtrace) as lf"
python3 "$here/quality_per_time.py" "$pt64" "$pt256" "$cy64" "$cy256" "${secs[pt_64_3]}" "${secs[pt_64_4]}" \
  "${secs[pt_256_3]}" "${secs[pt_256_4]}" "${secs[cy_64_3]}" "${secs[cy_64_4]}" "${secs[cy_256_3]}" "${secs[cy_256_4]}"
if [[ $glass == glass ]]; then
  cycles "$out/cy_glass.exr" 1024 3 GLASS >/dev/null
  "$lightfarm" run "$here/lightfarm_balls_lambert.lua" --set hdri=$hdri --set sun=$lf_sun --set seed=3 --set glass=1 \
    --set spp=1024 --output "$out/lf_glass.exr" --quiet 2>/dev/null
  echo "3. the front row rough glass, everything else Lambert, 1024 spp (columns: Cycles Principled GGX, lightfarm)"
  blender -b -P "$here/balls_peer.py" -- "$json" means "$out/cy_glass.exr" "$out/lf_glass.exr" 2>/dev/null | grep '^MEAN'
fi
