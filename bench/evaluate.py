#!/usr/bin/python3
"""The paper's evaluation (Morrical et al. 2019, §3) on real meshes, driving the `uvr` command.

For each case of the cases file (mesh, field, transfer function, camera, image size, backend) it renders every
mode (reference, skip, adaptive, full), sweeps s2 and p in full mode, renders a ground truth (reference at a much
smaller step), and writes into OUTDIR: report.md (tables), results.json, a montage of the images and one of the
sample heat maps per case, and plots (sweep_s2.png, sweep_p.png, speedup.png).

usage: bench/evaluate.py UVR OUTDIR [--cases bench/cases.json] [--data ../shared/data] [--quick]
                         [--only NAME ...] [--backend cpu] [--size WxH] [--frames N] [--vtk] [--keep-renders]
"""
import argparse
import json
import math
import os
import shutil
import subprocess
import sys
import tempfile
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import uvr_bench as ub  # noqa: E402

MODES = ["reference", "skip", "adaptive", "full"]


def slug(name):
    return "".join(c if c.isalnum() else "_" for c in name).strip("_")


def evaluate_case(uvr, case, data_dir, work, overrides):
    mesh = ub.resolve(case["mesh"], data_dir)
    tf = ub.resolve(case["tf"], data_dir)
    info = ub.mesh_info(uvr, mesh)
    field = ub.field_info(info, case["field"])
    camera = ub.camera_for(case, info)
    size = overrides.get("size") or case["size"]
    frames = overrides.get("frames") or case["frames"]
    sweep_frames = overrides.get("frames") or case["sweep_frames"]
    backend = overrides.get("backend") or case["backend"]
    name = slug(case["name"])
    common = ["--field", case["field"], "--tf", tf, "--tf-name", case["tf_name"], "--size", size,
              "--backend", backend, "--range", repr(field["min"]), repr(field["max"]), *ub.camera_args(camera)]

    def stem(tag):
        return os.path.join(work, f"{name}_{tag}")

    result = {"case": case, "mesh_path": mesh, "camera": camera, "size": size, "backend": backend,
              "field": field, "modes": {}, "s2_sweep": [], "p_sweep": []}
    started = time.time()

    ub.log(f"{case['name']}: reference")
    reference = ub.render(uvr, mesh, stem("reference"), common + ["--mode", "reference", "--frames", frames])
    s1, unit = reference["s1"], reference["unit"]
    steps = ["--s1", repr(s1), "--unit", repr(unit)]
    result["modes"]["reference"] = dict(reference, ssim=1.0, psnr=None, png=stem("reference") + ".png")
    for mode in MODES[1:]:
        ub.log(f"{case['name']}: {mode}")
        stats = ub.render(uvr, mesh, stem(mode), common + steps + ["--mode", mode, "--frames", frames])
        quality = ub.compare(uvr, stem("reference") + ".png", stem(mode) + ".png")
        result["modes"][mode] = dict(stats, **quality, png=stem(mode) + ".png")
    full = result["modes"]["full"]

    def sweep_point(tag, extra, reuse):
        if reuse:
            return dict(full, reused=True)
        ub.log(f"{case['name']}: full {' '.join(extra)}")
        stats = ub.render(uvr, mesh, stem(tag), common + steps + ["--mode", "full", "--frames", sweep_frames] + extra)
        return dict(stats, **ub.compare(uvr, stem("reference") + ".png", stem(tag) + ".png"))

    for factor in case["s2_factors"]:
        s2 = factor * s1
        point = sweep_point(f"s2_{factor}", ["--s2", repr(s2), "--p", repr(full["p"])],
                            math.isclose(s2, full["s2"], rel_tol=1e-5))
        result["s2_sweep"].append(dict(point, factor=factor))
    for p in case["p_values"]:
        point = sweep_point(f"p_{p}", ["--s2", repr(full["s2"]), "--p", repr(float(p))],
                            math.isclose(p, full["p"], rel_tol=1e-6))
        result["p_sweep"].append(dict(point, p_value=p))

    divisor = case["ground_truth_divisor"]
    if divisor:
        ub.log(f"{case['name']}: ground truth, s1/{divisor}")
        truth = ub.render(uvr, mesh, stem("truth"), common + ["--mode", "reference", "--s1", repr(s1 / divisor),
                                                             "--unit", repr(unit), "--frames", 1])
        result["truth"] = dict(truth, divisor=divisor, png=stem("truth") + ".png")
        for mode in ("reference", "full"):
            quality = ub.compare(uvr, stem("truth") + ".png", stem(mode) + ".png")
            result["modes"][mode]["ssim_truth"] = quality["ssim"]
            result["modes"][mode]["psnr_truth"] = quality["psnr"]
    result["wall_s"] = time.time() - started
    return result


def write_montages(results, outdir, thumb):
    images = os.path.join(outdir, "images")
    os.makedirs(images, exist_ok=True)
    for r in results:
        name = slug(r["case"]["name"])
        stems = [r["modes"][m]["png"][:-4] for m in MODES]
        labels = [f"{m} {r['modes'][m]['render_ms']:.0f} ms" for m in MODES]
        paths = [s + ".png" for s in stems]
        if "truth" in r:
            paths.append(r["truth"]["png"])
            labels.append(f"ground truth s1/{r['truth']['divisor']}")
        r["montage"] = os.path.join("images", name + ".png")
        ub.montage(paths, labels, os.path.join(outdir, r["montage"]), thumb)
        r["heatmaps"] = os.path.join("images", name + "_samples.png")
        ub.montage([s + "_samples.png" for s in stems],
                   [f"{m} {r['modes'][m]['samples_per_pixel_mean']:.1f} spp" for m in MODES],
                   os.path.join(outdir, r["heatmaps"]), thumb)


def plot_sweep(plt, results, key, parameter, label, log2, path):
    """Frame rate, samples and SSIM of `full` against one swept parameter, a line per case that sweeps it."""
    swept = [r for r in results if len(r[key]) > 1]
    if not swept:
        return
    figure, axes = plt.subplots(1, 3, figsize=(15, 4.2))
    for r in swept:
        xs = [p[parameter] for p in r[key]]
        axes[0].plot(xs, [1000.0 / p["render_ms"] for p in r[key]], "o-", label=r["case"]["name"])
        axes[1].plot(xs, [p["samples_per_pixel_mean"] for p in r[key]], "o-")
        axes[2].plot(xs, [p["ssim"] for p in r[key]], "o-")
    for axis, title in zip(axes, ["frames per second (full)", "samples per pixel (mean)", "SSIM against reference"]):
        if log2:
            axis.set_xscale("log", base=2)
        axis.set_xlabel(label)
        axis.set_title(title)
        axis.grid(True, alpha=0.3)
    axes[2].axhline(0.98, color="grey", linestyle="--", linewidth=0.8)
    figure.legend(loc="lower center", ncol=4, fontsize=8)
    figure.tight_layout(rect=(0, 0.12, 1, 1))
    figure.savefig(path, dpi=80)
    plt.close(figure)


def write_plots(results, outdir):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    plot_sweep(plt, results, "s2_sweep", "factor", "s2 / s1", True, os.path.join(outdir, "sweep_s2.png"))
    plot_sweep(plt, results, "p_sweep", "p_value", "p", False, os.path.join(outdir, "sweep_p.png"))

    figure, axis = plt.subplots(figsize=(max(6, 1.3 * len(results)), 4.5))
    width = 0.27
    for i, mode in enumerate(MODES[1:]):
        speedups = [r["modes"]["reference"]["render_ms"] / r["modes"][mode]["render_ms"] for r in results]
        axis.bar([x + (i - 1) * width for x in range(len(results))], speedups, width, label=mode)
    axis.axhline(1.0, color="black", linewidth=0.8)
    axis.set_xticks(range(len(results)))
    axis.set_xticklabels([r["case"]["name"].replace(" ", "\n", 1) for r in results], fontsize=7)
    axis.set_ylabel("speed-up over reference")
    axis.set_title("Speed-up per technique and transfer function")
    axis.legend()
    axis.grid(True, axis="y", alpha=0.3)
    figure.tight_layout()
    figure.savefig(os.path.join(outdir, "speedup.png"), dpi=80)
    plt.close(figure)


def write_report(results, outdir, command, machine_before, machine_after, total_s, vtk_section):
    f = ub.fmt
    lines = ["# Evaluation: space skipping and adaptive sampling on real meshes", ""]
    first = results[0]["modes"]["reference"]
    lines += [f"Machine: {machine_before['cpu']}, {machine_before['cores']} cores, {machine_before['memory_gib']} GiB; "
              f"uvr threads: {first['threads']}; backend: {results[0]['backend']}. Load average before / after: "
              f"{machine_before['load_average'][0]:.1f} / {machine_after['load_average'][0]:.1f} "
              "(the machine may be shared with other work: times are indicative).", "",
              f"Command: `{command}` ({total_s / 60:.1f} min).", "",
              "Render times are the median of the frames given (`--frames`); speed-up is reference time over the "
              "mode's time; SSIM and PSNR are `uvr compare` against the reference image of the same case; the "
              "ground truth is `reference` with s1 divided by the case's divisor, same opacity unit.", ""]

    lines += ["## Headline", "",
              "| case | kind | size | reference ms | full ms | speed-up | samples/pixel ref → full | "
              "SSIM full vs ref | SSIM ref vs truth | SSIM full vs truth |",
              "|---|---|---|---|---|---|---|---|---|---|"]
    for r in results:
        ref, full = r["modes"]["reference"], r["modes"]["full"]
        lines.append(f"| {r['case']['name']} | {r['case'].get('kind', '')} | {r['size']} | {f(ref['render_ms'], 0)} | "
                     f"{f(full['render_ms'], 0)} | {f(ref['render_ms'] / full['render_ms'], 2)}× | "
                     f"{f(ref['samples_per_pixel_mean'])} → {f(full['samples_per_pixel_mean'])} | "
                     f"{f(full['ssim'], 4)} | {f(ref.get('ssim_truth'), 4)} | {f(full.get('ssim_truth'), 4)} |")
    lines += ["", "![speed-up](speedup.png)", ""]
    if os.path.exists(os.path.join(outdir, "sweep_s2.png")):
        lines += ["![s2 sweep](sweep_s2.png)", ""]
    if os.path.exists(os.path.join(outdir, "sweep_p.png")):
        lines += ["![p sweep](sweep_p.png)", ""]

    lines += ["## Build and transfer-function update", "",
              "| case | cells | partitions | leaf size | load ms | build ms | TF update ms | s1 | s2 | p | unit | "
              "range | threads | backend |", "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for r in results:
        full = r["modes"]["full"]
        lines.append(f"| {r['case']['name']} | {full['cells']} | {full['partitions']} | {full['leaf_size']} | "
                     f"{f(full['load_ms'], 0)} | {f(full['build_ms'], 0)} | {f(full['tf_update_ms'], 2)} | "
                     f"{full['s1']:.4g} | {full['s2']:.4g} | {full['p']:g} | {full['unit']:.4g} | "
                     f"{full['range'][0]:.4g} – {full['range'][1]:.4g} | {full['threads']} | {full['backend']} |")
    lines.append("")

    for r in results:
        c = r["case"]
        lines += [f"## {c['name']}", "",
                  f"`{os.path.basename(r['mesh_path'])}`, field `{c['field']}` ({r['field']['centering']}), "
                  f"`{os.path.basename(c['tf'])}` \"{c['tf_name']}\", {r['size']}, camera eye "
                  f"{[round(x, 3) for x in r['camera']['eye']]} at {[round(x, 3) for x in r['camera']['at']]} "
                  f"up {r['camera']['up']} fovy {r['camera']['fovy']:g}; {r['wall_s']:.0f} s.", "",
                  "| mode | samples/pixel mean | max | render ms | frames/s | speed-up | SSIM | PSNR dB | "
                  "partitions skipped | SSIM vs truth |", "|---|---|---|---|---|---|---|---|---|---|"]
        ref_ms = r["modes"]["reference"]["render_ms"]
        for mode in MODES:
            m = r["modes"][mode]
            lines.append(f"| {mode} | {f(m['samples_per_pixel_mean'])} | {m['samples_per_pixel_max']} | "
                         f"{f(m['render_ms'], 0)} | {f(1000.0 / m['render_ms'], 2)} | {f(ref_ms / m['render_ms'], 2)}× | "
                         f"{f(m['ssim'], 4)} | {f(m['psnr'])} | {m['partitions_skipped']} / {m['partitions']} | "
                         f"{f(m.get('ssim_truth'), 4)} |")
        if "truth" in r:
            t = r["truth"]
            lines += ["", f"Ground truth: s1/{t['divisor']} = {t['s1']:.4g}, {f(t['samples_per_pixel_mean'])} "
                      f"samples/pixel, {f(t['render_ms'], 0)} ms."]
        for key, label, column in (("s2_sweep", "s2 / s1", "factor"), ("p_sweep", "p", "p_value")):
            if not r[key]:
                continue
            lines += ["", f"| {label} | s2 | p | samples/pixel mean | render ms | speed-up | SSIM | PSNR dB |",
                      "|---|---|---|---|---|---|---|---|"]
            for p in r[key]:
                lines.append(f"| {p[column]:g} | {p['s2']:.4g} | {p['p']:g} | {f(p['samples_per_pixel_mean'])} | "
                             f"{f(p['render_ms'], 0)} | {f(ref_ms / p['render_ms'], 2)}× | {f(p['ssim'], 4)} | "
                             f"{f(p['psnr'])} |")
        lines += ["", f"![images]({r['montage']})", "", f"![samples per pixel]({r['heatmaps']})", ""]

    if vtk_section:
        lines += [vtk_section, ""]
    with open(os.path.join(outdir, "report.md"), "w") as out:
        out.write("\n".join(lines))


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ub.add_case_arguments(parser)
    parser.add_argument("--backend", help="override every case's backend")
    parser.add_argument("--size", help="override every case's image size, WxH")
    parser.add_argument("--frames", help="override every case's frame count")
    parser.add_argument("--thumb", type=int, default=256, help="montage thumbnail size in pixels")
    parser.add_argument("--vtk", action="store_true", help="also run bench/vtk_compare.py into OUTDIR/vtk")
    parser.add_argument("--keep-renders", action="store_true", help="keep full-size renders in OUTDIR/renders")
    args = parser.parse_args()

    uvr = os.path.abspath(args.uvr)
    cases = ub.selected_cases(args, None)
    os.makedirs(args.outdir, exist_ok=True)
    command = "bench/evaluate.py " + " ".join(sys.argv[1:])
    before = ub.machine()
    started = time.time()
    work = os.path.join(args.outdir, "renders") if args.keep_renders else tempfile.mkdtemp(prefix="uvr-eval-")
    os.makedirs(work, exist_ok=True)
    overrides = {"backend": args.backend, "size": args.size, "frames": args.frames}
    try:
        results = [evaluate_case(uvr, case, args.data, work, overrides) for case in cases]
        write_montages(results, args.outdir, args.thumb)
        write_plots(results, args.outdir)
        vtk_section = None
        if args.vtk:
            vtk_out = os.path.join(args.outdir, "vtk")
            vtk_command = [sys.executable, os.path.join(ub.REPO, "bench", "vtk_compare.py"), uvr, vtk_out,
                           "--cases", args.cases, "--data", args.data] + (["--quick"] if args.quick else [])
            vtk_command += (["--only", *args.only] if args.only else []) + (["--size", args.size] if args.size else [])
            if not os.environ.get("DISPLAY") and shutil.which("xvfb-run"):
                vtk_command = ["xvfb-run", "-a"] + vtk_command
            subprocess.run(vtk_command, check=True)
            with open(os.path.join(vtk_out, "vtk_compare.md")) as f:
                vtk_section = f.read().replace("](", "](vtk/").replace("# ", "## ", 1)
        for r in results:
            for mode in r["modes"].values():
                mode.pop("png", None)
            r.get("truth", {}).pop("png", None)
        total = time.time() - started
        write_report(results, args.outdir, command, before, ub.machine(), total, vtk_section)
        with open(os.path.join(args.outdir, "results.json"), "w") as f:
            json.dump({"command": command, "machine": before, "total_s": total, "results": results}, f, indent=1)
    finally:
        if not args.keep_renders:
            shutil.rmtree(work, ignore_errors=True)
    ub.log(f"done in {time.time() - started:.0f} s: {os.path.join(args.outdir, 'report.md')}")


if __name__ == "__main__":
    main()
