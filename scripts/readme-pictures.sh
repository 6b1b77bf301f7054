#!/usr/bin/env bash
# The README's pictures from the demo's results: four of the heart's side-by-side pictures (rest | after)
# in a 2 x 2 montage, docs/img/readme_demo.png, half size. Run after scripts/demo.sh (or make demo):
#   scripts/readme-pictures.sh [DEMO_OUT]      (default build/demo/heart)
# Needs ffmpeg (scripts/install-deps.sh). Deterministic for the same pictures and ffmpeg version.
set -euo pipefail
cd "$(dirname "$0")/.."
demo=${1:-build/demo/heart}
pictures=(heart_grab heart_cut heart_retract heart_cut_suture)
for p in "${pictures[@]}"; do
  [[ -f $demo/$p.png ]] || { echo "readme-pictures: $demo/$p.png is missing: run scripts/demo.sh first" >&2; exit 2; }
done
command -v ffmpeg >/dev/null || { echo "readme-pictures: ffmpeg is missing: run scripts/install-deps.sh" >&2; exit 2; }
out=docs/img/readme_demo.png
tmp=$(mktemp --suffix=.png -p docs/img .readme_demo.XXXXXX)
trap 'rm -f "$tmp"' EXIT
ffmpeg -v error -y -i "$demo/${pictures[0]}.png" -i "$demo/${pictures[1]}.png" -i "$demo/${pictures[2]}.png" \
  -i "$demo/${pictures[3]}.png" -filter_complex \
  "[0]scale=770:-1:flags=area[a];[1]scale=770:-1:flags=area[b];[2]scale=770:-1:flags=area[c];[3]scale=770:-1:flags=area[d];[a][b]hstack=inputs=2[top];[c][d]hstack=inputs=2[bottom];[top][bottom]vstack=inputs=2" \
  -frames:v 1 -fflags +bitexact -flags:v +bitexact -f image2 -update 1 "$tmp"
[[ -s $tmp ]] || { echo "readme-pictures: ffmpeg wrote nothing" >&2; exit 1; }
chmod 644 "$tmp"
mv "$tmp" "$out"
trap - EXIT
echo "readme-pictures: wrote $out from $demo"
