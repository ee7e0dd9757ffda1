#!/usr/bin/env bash
# Renders every example farm with two lightfarm binaries and compares the images bit for bit (EXR, linear float).
# Used to prove that a refactoring changes no pixel:
#
#   git worktree add /tmp/before <old-commit> && cmake -S /tmp/before -B /tmp/before/build && cmake --build ...
#   tests/tools/compare_examples.sh /tmp/before/build/lightfarm build/lightfarm          # small sizes (~2 min)
#   tests/tools/compare_examples.sh /tmp/before/build/lightfarm build/lightfarm --full   # as the examples are
#
# Pixels are compared by tests/image_equal (EXR headers carry the time they were written). Exit status 0 when every image is identical, 1 otherwise. Images stay in $KEEP (default: a temporary folder).
set -euo pipefail
before=$(realpath "$1"); after=$(realpath "$2"); full=${3:-}
here=$(cd "$(dirname "$0")/../.." && pwd)
out=${KEEP:-$(mktemp -d /tmp/lf-compare.XXXXXX)}
mkdir -p "$out"
equal=${IMAGE_EQUAL:-$(dirname "$after")/tests/image_equal}  # built with the tests

# example, then the --set overrides that keep it quick (ignored with --full)
cases=(
  "cornell.lua|width=128 height=128 spp=4"
  "cornell_pool.lua|width=128 height=128 spp=4"
  "pathtrace.lua|width=96 height=96 spp=4"
  "cornell_glass.lua|width=96 height=96 spp=2 photons=100000 prepass=2000"
  "cornell_glass_radiosity.lua|width=96 height=96 spp=2 photons=50000"
  "radiosity_room.lua|width=96 height=72 spp=2 iterations=60"
  "plugin-python/tinted_cornell.lua|"
  "material_balls.lua|width=96 height=54 spp=4"
  "product_shot.lua|width=96 height=54 spp=4"
)

failed=0
for c in "${cases[@]}"; do
  script=${c%%|*}; sets=${c#*|}
  args=()
  if [ "$full" != "--full" ]; then for s in $sets; do args+=(--set "$s"); done; fi
  name=$(echo "$script" | tr '/' '_'); name=${name%.lua}
  for side in before after; do
    bin=$before; [ $side = after ] && bin=$after
    # Radiosity examples write a PLY beside the image; run each side in its own folder.
    mkdir -p "$out/$side"
    (cd "$out/$side" && "$bin" run "$here/examples/$script" "${args[@]}" --output "$out/$side/$name.exr" --quiet) \
      || { echo "FAIL $script: the $side binary exited with $?"; failed=1; continue 2; }
  done
  if why=$("$equal" "$out/before/$name.exr" "$out/after/$name.exr"); then
    echo "same  $script"
  else
    echo "DIFF  $script: $why"; failed=1
  fi
done
exit $failed
