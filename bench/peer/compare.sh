#!/usr/bin/env bash
# Quality per time against Cycles, measured the way bench/peer/README.md describes (issue 16): each renderer at 64
# and 256 spp with seeds 3 and 4 on the empty Cornell box (256x256, 2 cores), its noise from the seed pair
# (pair_noise.py, no reference), its seconds (Cycles: its render call; lightfarm: the whole run), and the time
# lightfarm takes to reach Cycles' 256-spp noise as a share of Cycles' time (noise falling as spp^-slope, the slope
# measured between 64 and 256). Needs `blender` (Debian's, 3.4) and a built lightfarm.
#
#   bench/peer/compare.sh [LIGHTFARM] [-- LIGHTFARM_SETS...] [--cycles-min-light-bounces N]
#   e.g. bench/peer/compare.sh build/lightfarm -- roulette=sqrt rr_depth=5 --cycles-min-light-bounces 3
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
lightfarm=${1:-$here/../../build/lightfarm}
shift || true
sets=()
min_bounces=0
if [[ ${1:-} == "--" ]]; then
  shift
  while [[ $# -gt 0 && $1 != --cycles-min-light-bounces ]]; do sets+=(--set "$1"); shift; done
fi
if [[ ${1:-} == --cycles-min-light-bounces ]]; then min_bounces=$2; fi
command -v blender >/dev/null || { echo "compare.sh: needs blender (apt-get install blender)" >&2; exit 2; }
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
declare -A secs
for spp in 64 256; do
  for seed in 3 4; do
    t0=$EPOCHREALTIME
    "$lightfarm" run "$here/lightfarm_cornell.lua" --set spp=$spp --set seed=$seed "${sets[@]}" --output "$out/lf_${spp}_$seed.exr" --quiet
    secs[lf_${spp}_$seed]=$(python3 -c "print($EPOCHREALTIME - $t0)")
    secs[cy_${spp}_$seed]=$(blender -b -P "$here/cycles_cornell.py" -- "$out/cy_${spp}_$seed.exr" $spp 256 $seed $min_bounces 2>/dev/null |
                            awk '/RENDER_SECONDS/ {print $2}')
  done
done
noise=$(blender -b -P "$here/pair_noise.py" -- "$out/lf_256_3.exr" \
          "$out/lf_64_3.exr" "$out/lf_64_4.exr" "$out/lf_256_3.exr" "$out/lf_256_4.exr" \
          "$out/cy_64_3.exr" "$out/cy_64_4.exr" "$out/cy_256_3.exr" "$out/cy_256_4.exr" 2>/dev/null | awk '/^NOISE/ {print $4}')
read -r lf64 lf256 cy64 cy256 <<<"$(echo $noise)"
echo "lightfarm ${sets[*]:-(defaults)} against Cycles (min_light_bounces $min_bounces); 256x256, seeds 3 and 4"
python3 "$here/quality_per_time.py" "$lf64" "$lf256" "$cy64" "$cy256" "${secs[lf_64_3]}" "${secs[lf_64_4]}" \
  "${secs[lf_256_3]}" "${secs[lf_256_4]}" "${secs[cy_64_3]}" "${secs[cy_64_4]}" "${secs[cy_256_3]}" "${secs[cy_256_4]}"
