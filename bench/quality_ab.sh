#!/usr/bin/env bash
# CPU quality A/B on one case: SSIM against a converged image (reference, pre-integrated, s1/4) and frame time
# of an older build's `full` and of this build's modes and variants, all at the same opacity unit (this build's
# default). usage: bench/quality_ab.sh NEW_UVR OLD_UVR MESH FIELD TF_FILE TF_NAME OUT_DIR [camera options...]
# (OLD_UVR takes FIELD without a point:/cell: prefix.)
set -euo pipefail
new=$1 old=$2 mesh=$3 field=$4 tf=$5 tfName=$6 out=$7; shift 7
mkdir -p "$out"
"$new" render "$mesh" --field "$field" --size 8x8 -o "$out/probe.png" --stats "$out/probe.json" 2>/dev/null
read -r unit s1 < <(python3 -c "import json,sys;d=json.load(open(sys.argv[1]));print(d['unit'],d['s1'])" "$out/probe.json")
common=(--size 512x512 --tf "$tf" --tf-name "$tfName" --unit "$unit" "$@")
"$new" render "$mesh" --field "$field" "${common[@]}" --mode reference --compositing preintegrated --steps global \
  --s1 "$(python3 -c "print($s1 / 4)")" -o "$out/truth.png" 2>/dev/null
run() { # NAME BINARY FIELD [options...]
  local name=$1 bin=$2 f=$3; shift 3
  "$bin" render "$mesh" --field "$f" "${common[@]}" "$@" -o "$out/$name.png" --stats "$out/$name.json" 2>/dev/null
  python3 - "$out/$name.json" "$name" "$("$new" compare "$out/truth.png" "$out/$name.png" --json)" <<'PY'
import json, sys
s = json.load(open(sys.argv[1]))
print(f"| {sys.argv[2]} | {s['render_ms']:.0f} | {s['samples_per_pixel_mean']:.1f} | {json.loads(sys.argv[3])['ssim']:.4f} |")
PY
}
echo "| variant | ms per frame | samples per pixel | SSIM vs converged |"
echo "|---|---|---|---|"
run old_full "$old" "${field#*:}"
run full "$new" "$field"
run full_point_global "$new" "$field" --compositing point --steps global
run reference "$new" "$field" --mode reference
run full_half_s1 "$new" "$field" --s1 "$(python3 -c "print($s1 / 2)")" --s2 "$(python3 -c "print($s1 * 8)")"
