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
python3 - "$lf64" "$lf256" "$cy64" "$cy256" "${secs[lf_64_3]}" "${secs[lf_64_4]}" "${secs[lf_256_3]}" "${secs[lf_256_4]}" \
  "${secs[cy_64_3]}" "${secs[cy_64_4]}" "${secs[cy_256_3]}" "${secs[cy_256_4]}" "${sets[*]:-}" "$min_bounces" <<'PY'
import math, sys
a = sys.argv[1:]
lf64, lf256, cy64, cy256 = map(float, a[0:4])
t = list(map(float, a[4:12]))
lf_t64, lf_t256, cy_t64, cy_t256 = (t[0] + t[1]) / 2, (t[2] + t[3]) / 2, (t[4] + t[5]) / 2, (t[6] + t[7]) / 2
print("lightfarm %s against Cycles (min_light_bounces %s); 256x256, seeds 3 and 4" % (a[12] or "(defaults)", a[13]))
print("%-10s %10s %10s %12s" % ("", "noise", "seconds", "noise^2 x s"))
for name, n, s in (("lf 64", lf64, lf_t64), ("lf 256", lf256, lf_t256), ("cy 64", cy64, cy_t64), ("cy 256", cy256, cy_t256)):
    print("%-10s %10.5f %10.2f %12.5f" % (name, n, s, n * n * s))
slope = math.log(lf64 / lf256) / math.log(4)
spp = 256 * (lf256 / cy256) ** (1 / slope)
# lightfarm's time grows with its samples from a fixed start (launch, setup): the line through its two points.
per_spp = (lf_t256 - lf_t64) / 192
fixed = lf_t256 - 256 * per_spp
lf_time = fixed + per_spp * spp
print("lightfarm reaches Cycles' 256-spp noise at ~%.0f spp (its noise falls as spp^-%.2f) in ~%.1f s: %.2f of Cycles' %.1f s"
      % (spp, slope, lf_time, lf_time / cy_t256, cy_t256))
PY
