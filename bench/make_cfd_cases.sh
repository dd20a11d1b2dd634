#!/bin/bash
# Makes benchmark meshes from real solver runs: OpenFOAM's windAroundBuildings and turbineSiting tutorials
# (snappyHexMesh meshes of hexahedra, prisms, pyramids, tets and polyhedra), meshed and run with simpleFoam
# from scratch, then exported by foamToVTK at the last time step twice: polyhedra kept (`*_poly.vtu`, VTK type
# 42) and split by foamToVTK into tets and pyramids (`*_decomp.vtu`). Fields U and p, cell data and point data
# (foamToVTK writes both under the same names).
#
#   bench/make_cfd_cases.sh [OUT_DIR] [CASE...]     (default ../shared/cfd, both cases)
#
# Needs Debian's openfoam and openfoam-examples (OpenFOAM v1912). The runs are cut short to keep each case to
# a few minutes on 2 cores (ITERATIONS below; the tutorials run 400 and 5000): the flow has developed around
# the obstacles (initial residuals at the last step: windAroundBuildings U 1e-3 to 4e-3, p 3e-2;
# turbineSiting U 4e-5, p 1e-4). Set ITERATIONS to change that. Serial runs (the tutorials decompose
# turbineSiting for 4 processes). On the 2-core development machine: windAroundBuildings 193 s, turbineSiting
# 56 s (20 and 7 minutes while 3 builds ran). windAroundBuildings: 185,237 cells (171,484 hexahedra, 1,102
# prisms, 12,651 polyhedra), 218,801 points; turbineSiting: 120,246 cells (107,146 hexahedra, 750 prisms,
# 12,350 polyhedra), 144,990 points. Writes OUT_DIR/CASE/ (the case, its logs) and
# OUT_DIR/CASE_{poly,decomp}.vtu (18-30 MB each).
set -euo pipefail

here="$(cd "$(dirname "$0")" && pwd)"
out="${1:-$here/../../shared/cfd}"
shift || true
cases=("$@")
[ ${#cases[@]} -gt 0 ] || cases=(windAroundBuildings turbineSiting)
ITERATIONS="${ITERATIONS:-}"

tutorials=/usr/share/doc/openfoam-examples/examples/incompressible/simpleFoam
[ -d "$tutorials" ] || { echo "make_cfd_cases: $tutorials missing (apt-get install openfoam-examples)" >&2; exit 1; }
command -v simpleFoam >/dev/null || { echo "make_cfd_cases: simpleFoam missing (apt-get install openfoam)" >&2; exit 1; }
# Debian's binaries find etc/controlDict through WM_PROJECT_DIR; its etc/bashrc needs tools Debian leaves out.
export WM_PROJECT_DIR=/usr/share/openfoam

mkdir -p "$out"
out="$(cd "$out" && pwd)"

run() { # run LOG COMMAND...: quietly, the log kept; the log's tail on failure
  local log="$1"
  shift
  if ! "$@" >"$log" 2>&1; then
    echo "make_cfd_cases: '$*' failed, see $log:" >&2
    tail -20 "$log" >&2
    exit 1
  fi
}

setControl() { # setControl KEY VALUE: in system/controlDict
  sed -i -E "s/^($1[[:space:]]+)[^;]*;/\1$2;/" system/controlDict
}

prepare() { # prepare CASE ITERATIONS: a fresh copy, decompressed, without the tutorial's post-processing
  local name="$1" iterations="$2"
  rm -rf "$out/$name"
  cp -r "$tutorials/$name" "$out/$name"
  chmod -R u+w "$out/$name"
  cd "$out/$name"
  find . -name '*.gz' -exec gunzip -f {} +
  # The function objects (ensight, VTK, rendering, profiling) cost time and need libraries Debian may lack.
  sed -i '/^functions/,$d' system/controlDict
  setControl endTime "$iterations"
  setControl writeInterval "$iterations"
  setControl writeFormat binary
}

export_vtk() { # export_vtk CASE: the last time step, polyhedra kept and decomposed
  local name="$1"
  rm -rf VTK-poly VTK-decomp
  run log.foamToVTK.poly foamToVTK -latestTime -fields '(U p)' -no-boundary -no-lagrangian -name VTK-poly
  run log.foamToVTK.decomp foamToVTK -latestTime -fields '(U p)' -no-boundary -no-lagrangian -poly-decomp \
    -name VTK-decomp
  local poly decomp
  poly="$(find VTK-poly -name '*.vtu' | sort | tail -1)"
  decomp="$(find VTK-decomp -name '*.vtu' | sort | tail -1)"
  cp "$poly" "$out/${name}_poly.vtu"
  cp "$decomp" "$out/${name}_decomp.vtu"
  echo "$name: $out/${name}_poly.vtu $out/${name}_decomp.vtu"
}

windAroundBuildings() {
  prepare windAroundBuildings "${ITERATIONS:-150}"
  run log.surfaceFeatureExtract surfaceFeatureExtract
  run log.blockMesh blockMesh
  run log.snappyHexMesh snappyHexMesh -overwrite
  rm -rf 0 && cp -r 0.orig 0
  run log.simpleFoam simpleFoam
  export_vtk windAroundBuildings
}

turbineSiting() {
  prepare turbineSiting "${ITERATIONS:-150}"
  rm -rf 0 && mkdir 0
  run log.blockMesh blockMesh
  run log.snappyHexMesh snappyHexMesh -overwrite
  find . -iname '*level*' -type f -delete
  rm -rf 0 && cp -r 0.orig 0
  run log.topoSet topoSet
  run log.simpleFoam simpleFoam
  export_vtk turbineSiting
}

for c in "${cases[@]}"; do
  start=$SECONDS
  case "$c" in
  windAroundBuildings | turbineSiting) "$c" ;;
  *) echo "make_cfd_cases: unknown case '$c'" >&2; exit 1 ;;
  esac
  echo "$c: $((SECONDS - start)) s"
done
