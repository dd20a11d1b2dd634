#!/bin/bash
# Makes a time series from a transient solver run: OpenFOAM's pimpleFoam TJunction tutorial (a 3-D T-shaped
# duct of hexahedra, 0.22 x 0.42 x 0.02 m; the inlet's total pressure ramps from 10 to 40 over the first second,
# and a passive scalar `s`, injected at a unit rate everywhere, is the age of the fluid), its mesh refined
# REFINE times along each axis, run to 1.5 s and written every WRITE_INTERVAL s; foamToVTK exports every
# written time (fields U, p and s, cell and point data) and a ParaView collection lists them in order:
# OUT_DIR/tjunction/VTK/*.vtu and OUT_DIR/tjunction.pvd. Every step has the same points and cells, so
# `uvr render --time-step all` keeps the acceleration data from step to step.
#
#   bench/make_cfd_series.sh [OUT_DIR]      (default ../shared/cfd)
#
# Needs Debian's openfoam and openfoam-examples (OpenFOAM v1912). With the defaults (REFINE=2: 31,000
# hexahedra, 37,631 points; WRITE_INTERVAL=0.05: 31 steps, the initial one included; 118 MB of .vtu) pimpleFoam
# took 3.7 CPU-minutes and the whole script 9 minutes wall on the 2-core development machine while other
# builds ran (load average about 5.5).
set -euo pipefail

here="$(cd "$(dirname "$0")" && pwd)"
out="${1:-$here/../../shared/cfd}"
REFINE="${REFINE:-2}"
WRITE_INTERVAL="${WRITE_INTERVAL:-0.05}"

tutorial=/usr/share/doc/openfoam-examples/examples/incompressible/pimpleFoam/RAS/TJunction
[ -d "$tutorial" ] || { echo "make_cfd_series: $tutorial missing (apt-get install openfoam-examples)" >&2; exit 1; }
command -v pimpleFoam >/dev/null || { echo "make_cfd_series: pimpleFoam missing (apt-get install openfoam)" >&2; exit 1; }
# Debian's binaries find etc/controlDict through WM_PROJECT_DIR; its etc/bashrc needs tools Debian leaves out.
export WM_PROJECT_DIR=/usr/share/openfoam

mkdir -p "$out"
out="$(cd "$out" && pwd)"
case="$out/tjunction"

run() { # run LOG COMMAND...: quietly, the log kept; the log's tail on failure
  local log="$1"
  shift
  if ! "$@" >"$log" 2>&1; then
    echo "make_cfd_series: '$*' failed, see $case/$log:" >&2
    tail -20 "$log" >&2
    exit 1
  fi
}

start=$SECONDS
rm -rf "$case"
cp -r "$tutorial" "$case"
chmod -R u+w "$case"
cd "$case"
find . -name '*.gz' -exec gunzip -f {} +
# Each block's cell counts, e.g. (50 5 5), times REFINE.
REFINE="$REFINE" perl -pi -e \
  's/\((\d+) (\d+) (\d+)\) simpleGrading/"(" . join(" ", map { $_ * $ENV{REFINE} } $1, $2, $3) . ") simpleGrading"/e' \
  system/blockMeshDict
sed -i -E "s/^(writeInterval[[:space:]]+)[^;]*;/\1$WRITE_INTERVAL;/; s/^(writeFormat[[:space:]]+)[^;]*;/\1binary;/" \
  system/controlDict
run log.blockMesh blockMesh
run log.pimpleFoam pimpleFoam
run log.foamToVTK foamToVTK -fields '(U p s)' -no-boundary -no-lagrangian

# foamToVTK names each time's folder by its time index; its .vtm.series lists them with their times.
python3 - "$case/VTK" "$out/tjunction.pvd" <<'EOF'
import json, os, sys
vtk, pvd = sys.argv[1], sys.argv[2]
series = json.load(open(os.path.join(vtk, "tjunction.vtm.series")))
rows = []
for entry in series["files"]:
    piece = os.path.join(os.path.relpath(vtk, os.path.dirname(pvd)), entry["name"][:-len(".vtm")], "internal.vtu")
    rows.append('  <DataSet timestep="%g" file="%s"/>' % (entry["time"], piece))
with open(pvd, "w") as f:
    f.write('<?xml version="1.0"?>\n<VTKFile type="Collection" version="0.1">\n<Collection>\n')
    f.write("\n".join(rows) + "\n</Collection>\n</VTKFile>\n")
print("tjunction: %d steps in %s" % (len(rows), pvd))
EOF
echo "tjunction: $((SECONDS - start)) s"
