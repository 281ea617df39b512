#!/usr/bin/env bash
# Installs what is missing, builds (Release) and runs the default scene; prints where the results are.
set -euo pipefail
here=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
"$here/tools/setup.sh"
build="${SPHFSI_BUILD_DIR:-$here/build}"
scene="${1:-$here/scenarios/elastic_gate.toml}"
name=$(basename "$scene" .toml)
out="$here/out/$name"
"$build/bin/sphfsi" run "$scene" --out "$out" --overwrite  # the demo's own folder: each run replaces the last
if [ -f "$out/watchpoints.csv" ]; then
  refs=()
  if [ "$name" = elastic_gate ]; then  # the experiment's tip displacements
    refs=(--ref "tip dx=$here/scenarios/reference/antoci2007_gate_tip_dx.csv"
          --ref "tip dy=$here/scenarios/reference/antoci2007_gate_tip_dy.csv")
  fi
  /usr/bin/python3 "$here/tools/plot_watchpoints.py" "$out/watchpoints.csv" "$out/watchpoints.png" "${refs[@]}"
fi
echo "results in $out"
