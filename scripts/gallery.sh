#!/usr/bin/env bash
# Renders the example scenes of configs/ to docs/img/<scene>.png with
# `pdyn render`, for the README's gallery. Each scene is drawn at one moment
# that shows what it is about, from the view that shows it best.
#
#   bash scripts/gallery.sh [PDYN]     (default build/bin/pdyn; build it first)
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."
pdyn="${1:-build/bin/pdyn}"
mkdir -p docs/img

# scene    time (s)   view
shots=(
  "demo            1.0   3d"
  "hanging_cloth   0.3   3d"
  "drop            1.0   xz"
  "bouncing_ball   0.9   xz"
  "cloud           0.8   3d"
  "pendulum        0.6   xz"
  "vortex          2.0   xy"
  "flag            1.5   3d"
  "orbit           1.0   xy"
  "rope_over_sphere 1.5  xz"
  "jelly_in_box    0.6   3d"
  "blob            1.0   xz"
  "cloth_on_heap   2.0   3d"
  "granular_column 4.0   xz"
  "lj_liquid       5.0   3d"
  "galaxies        3.0   xy"
)
for shot in "${shots[@]}"; do
  read -r scene t view <<<"$shot"
  if [[ ! -f "configs/$scene.yaml" ]]; then
    echo "gallery: configs/$scene.yaml not found, skipped" >&2
    continue
  fi
  "$pdyn" render "configs/$scene.yaml" --at "$t" --view "$view" --size 600x400 \
    --png "docs/img/$scene.png" --quiet
  echo "gallery: docs/img/$scene.png (t = $t s, view $view)"
done
