# python3 quality_per_time.py LF64 LF256 CY64 CY256 LF_T64_A LF_T64_B LF_T256_A LF_T256_B CY_T64_A CY_T64_B CY_T256_A CY_T256_B
# Each renderer's noise at 64 and 256 spp and the seconds of its two runs at each: the table compare.sh and
# compare_balls.sh print, and the time lightfarm takes to reach Cycles' 256-spp noise as a share of Cycles' time
# (lightfarm's noise falling as spp^-slope, the slope measured between 64 and 256; its time a fixed start plus a
# cost per sample, the line through its two points).
import math
import sys

a = list(map(float, sys.argv[1:13]))
lf64, lf256, cy64, cy256 = a[0:4]
lf_t64, lf_t256, cy_t64, cy_t256 = (a[4] + a[5]) / 2, (a[6] + a[7]) / 2, (a[8] + a[9]) / 2, (a[10] + a[11]) / 2
print("%-10s %10s %10s %12s" % ("", "noise", "seconds", "noise^2 x s"))
for name, n, s in (("lf 64", lf64, lf_t64), ("lf 256", lf256, lf_t256), ("cy 64", cy64, cy_t64), ("cy 256", cy256, cy_t256)):
    print("%-10s %10.5f %10.2f %12.5f" % (name, n, s, n * n * s))
slope = math.log(lf64 / lf256) / math.log(4)
spp = 256 * (lf256 / cy256) ** (1 / slope)
per_spp = (lf_t256 - lf_t64) / 192
fixed = lf_t256 - 256 * per_spp
lf_time = fixed + per_spp * spp
print("lightfarm reaches Cycles' 256-spp noise at ~%.0f spp (its noise falls as spp^-%.2f) in ~%.1f s: %.2f of Cycles' %.1f s"
      % (spp, slope, lf_time, lf_time / cy_t256, cy_t256))
