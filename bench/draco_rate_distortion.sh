#!/usr/bin/env bash
# Rate-distortion of isowave against Draco on the same extracted isosurface.
# Draco (Debian package `draco`, installed here if missing and running as
# root) compresses the extracted triangle mesh at several position
# quantizations; isowave converts the volume and decodes at several
# coefficient percentages. Both are measured the same way: file bytes, bits
# per isosurface vertex, and in percent of a cell the RMS / max distance of
# the decoded vertices to the extracted surface and of the extracted vertices
# to the decoded surface (what the decoded mesh fails to cover).
#
# usage: bench/draco_rate_distortion.sh [VOLUME ISO [CELL [convert/extract options...]]]
#   default: ../shared/data/volumes/miranda_256x256x256.nrrd 1.5 1 --min-component-vertices 50
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
build="${ISOWAVE_BUILD_DIR:-$root/build}"
volume="${1:-$root/../shared/data/volumes/miranda_256x256x256.nrrd}"
iso="${2:-1.5}"
cell="${3:-1}"
shift $(( $# > 3 ? 3 : $# )) || true
options=("$@")
[ $# -eq 0 ] && [ "$volume" = "$root/../shared/data/volumes/miranda_256x256x256.nrrd" ] && options=(--min-component-vertices 50)

if ! command -v draco_encoder >/dev/null; then
  if [ "$(id -u)" -eq 0 ]; then
    DEBIAN_FRONTEND=noninteractive apt-get install -y -qq draco >/dev/null
  else
    echo "draco_encoder not found: install the Debian package 'draco'" >&2
    exit 1
  fi
fi
ISOWAVE_BUILD_TARGET=isowave "$root/scripts/build"
ISOWAVE_BUILD_TARGET=bench_mesh_distance "$root/scripts/build"
isowave="$build/bin/isowave"
distance="$build/bench/bench_mesh_distance"
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT

"$isowave" extract "$volume" --iso "$iso" "${options[@]}" -o "$work/surface.ply" >/dev/null
vertices=$(head -c 400 "$work/surface.ply" | grep -a "element vertex" | awk '{print $3}')
echo "isosurface: $vertices vertices ($volume, iso $iso ${options[*]})"
printf "\n%-22s %12s %12s %14s %14s %14s %14s\n" "method" "bytes" "bits/vertex" "RMS to surf." "max to surf." "RMS coverage" "max coverage"

for qp in 8 10 11 12 14 16; do
  draco_encoder -i "$work/surface.ply" -o "$work/q.drc" -qp "$qp" -cl 7 >/dev/null
  draco_decoder -i "$work/q.drc" -o "$work/q.ply" >/dev/null
  bytes=$(stat -c %s "$work/q.drc")
  read -r rms max back_rms back_max < <("$distance" "$work/q.ply" "$work/surface.ply" "$cell")
  printf "%-22s %12d %12.3f %14.3f %14.3f %14.3f %14.3f\n" "draco -qp $qp" "$bytes" "$(awk -v b="$bytes" -v v="$vertices" 'BEGIN { print 8 * b / v }')" "$rms" "$max" "$back_rms" "$back_max"
done

"$isowave" convert "$volume" --iso "$iso" "${options[@]}" -o "$work/surface.isw" --quiet --force
"$isowave" stats "$work/surface.isw" --percents 100,50,20,10,5 --csv > "$work/stats.csv"
while IFS=, read -r coefficients percent rmse max bytes bits_fine bits_iso base; do
  [ "$coefficients" = coefficients ] && continue
  decode_percent="$percent"
  label="isowave ${percent}%"
  if [ "$base" = 1 ]; then decode_percent=0; label="isowave base mesh"; fi
  "$isowave" decode "$work/surface.isw" --percent "$decode_percent" -o "$work/d.ply" --quiet --force
  read -r rms max back_rms back_max < <("$distance" "$work/d.ply" "$work/surface.ply" "$cell")
  printf "%-22s %12d %12.3f %14.3f %14.3f %14.3f %14.3f\n" "$label" "$bytes" "$(awk -v b="$bytes" -v v="$vertices" 'BEGIN { print 8 * b / v }')" "$rms" "$max" "$back_rms" "$back_max"
done < "$work/stats.csv"
