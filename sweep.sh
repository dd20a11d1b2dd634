#!/usr/bin/env bash
# temporary: leaf-size sweep on the GPU
set -u
out=$1; mkdir -p $out
prefix=/tmp/uvr-deps; mkdir -p $prefix
for f in .deps/*.deb; do dpkg -x "$f" $prefix; done
lib=$prefix/usr/lib/x86_64-linux-gnu
ln -sf "$(ls /lib/x86_64-linux-gnu/libz.so.1* /usr/lib/x86_64-linux-gnu/libz.so.1* 2>/dev/null | head -1)" $lib/libz.so
export LD_LIBRARY_PATH=$lib:${LD_LIBRARY_PATH:-}
cmake -S . -B build-gpu -DCMAKE_BUILD_TYPE=Release -DUVR_CUDA=ON -DCMAKE_PREFIX_PATH=$prefix/usr \
     -DCMAKE_LIBRARY_PATH=$lib -DCMAKE_INCLUDE_PATH=$prefix/usr/include >$out/build.log 2>&1 &&
   cmake --build build-gpu -j16 --target uvr >>$out/build.log 2>&1 || { tail -20 $out/build.log; exit 1; }
uvr=build-gpu/uvr
$uvr gen shared-data/ch2better.nii.gz --cells 12000000 -o /tmp/g12.umesh > $out/gen.log 2>&1
for mesh in shared-data/brain_t1_tet_857k.vtu /tmp/g12.umesh; do
  case $mesh in *.vtu) args="--field T1";; *) args="--field ch2better --range 0 125";; esac
  for tf in Binary Translucent; do
    $uvr render $mesh $args --tf data/presets/brain.json --tf-name "Brain $tf" --mode reference --backend cuda --frames 20 -o $out/r.png --stats $out/r.json 2>/dev/null
    python3 -c "import json;s=json.load(open('$out/r.json'));print('$(basename $mesh) $tf reference', 'ms %.2f spp %.1f'%(s['render_ms'],s['samples_per_pixel_mean']))"
    for leaf in 64 512 4096 32768; do for mode in skip full; do
      $uvr render $mesh $args --tf data/presets/brain.json --tf-name "Brain $tf" --mode $mode --leaf-size $leaf --backend cuda --frames 20 -o $out/m.png --stats $out/m.json 2>/dev/null
      ssim=$($uvr compare $out/r.png $out/m.png --json | python3 -c 'import json,sys;print(json.load(sys.stdin)["ssim"])')
      python3 -c "import json;s=json.load(open('$out/m.json'));print('$(basename $mesh) $tf $mode leaf $leaf', 'parts %d skipped %d ms %.2f spp %.1f ssim %.4f bytes/cell %.0f'%(s['partitions'],s['partitions_skipped'],s['render_ms'],s['samples_per_pixel_mean'],$ssim,s['gpu_scene_bytes']/s['cells']))"
    done; done
  done
done
