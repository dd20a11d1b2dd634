"""What bench/evaluate.py and bench/vtk_compare.py share: reading the cases file, running `uvr`, the camera both
renderers get, image montages and the machine's description."""
import json
import math
import os
import platform
import statistics
import subprocess
import sys
import time

REPO = os.path.normpath(os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))


def log(message):
    print(f"[{time.strftime('%H:%M:%S')}] {message}", file=sys.stderr, flush=True)


def run(command):
    """Runs a command; exits with its stderr when it fails. Returns stdout."""
    result = subprocess.run([str(c) for c in command], capture_output=True, text=True)
    if result.returncode != 0:
        sys.exit(f"failed ({result.returncode}): {' '.join(map(str, command))}\n{result.stderr}")
    return result.stdout


def add_case_arguments(parser):
    """The arguments every driver takes: the uvr binary, the output folder and which cases to run."""
    parser.add_argument("uvr")
    parser.add_argument("outdir")
    parser.add_argument("--cases", default=os.path.join(REPO, "bench", "cases.json"))
    parser.add_argument("--data", default=os.path.join(REPO, "..", "shared", "data"))
    parser.add_argument("--quick", action="store_true", help="the small smoke-test cases of the cases file")
    parser.add_argument("--only", nargs="+", help="only the cases whose name contains one of these")


def selected_cases(args, section):
    """The cases of `section` that add_case_arguments' --quick and --only select."""
    cases = load_cases(args.cases, section, args.quick)
    cases = [c for c in cases if not args.only or any(o in c["name"] for o in args.only)]
    # Cases on data made apart (bench/make_cfd_cases.sh) are skipped where it was not made.
    kept = []
    for c in cases:
        mesh = resolve(c["mesh"], args.data)
        if c.get("optional") and not os.path.exists(mesh):
            log(f"{c['name']}: skipped, {mesh} is absent ({c['optional']})")
            continue
        kept.append(c)
    return kept


def load_cases(path, section, quick):
    """Cases of `section` (None: the top level) of the cases file, each merged over its defaults."""
    with open(path) as f:
        document = json.load(f)
    if section:
        document = document[section]
    if quick:
        base = dict(document.get("defaults", {}))
        base.update(document["quick"].get("defaults", {}))
        cases = document["quick"]["cases"]
    else:
        base, cases = document.get("defaults", {}), document["cases"]
    merged = []
    for case in cases:
        full = dict(base)
        full.update(case)
        merged.append(full)
    return merged


def resolve(path, data_dir):
    if path.startswith("$DATA/"):
        return os.path.join(data_dir, path[len("$DATA/"):])
    return path if os.path.isabs(path) else os.path.join(REPO, path)


_info_cache = {}


def mesh_info(uvr, mesh):
    if mesh not in _info_cache:
        _info_cache[mesh] = json.loads(run([uvr, "info", mesh, "--json"]))
    return _info_cache[mesh]


def field_info(info, name):
    """The field `uvr render --field name` renders: "point:p" or "cell:p" by centring, a plain name the point
    field where a point and a cell field share it."""
    for prefix in ("point", "cell"):
        if name.startswith(prefix + ":"):
            for field in info["fields"]:
                if field["name"] == name[len(prefix) + 1:] and field["centering"] == prefix:
                    return field
    named = [f for f in info["fields"] if f["name"] == name]
    if named:
        return next((f for f in named if f["centering"] == "point"), named[0])
    sys.exit(f"no field {name}; fields: {[f['name'] for f in info['fields']]}")


def camera_for(case, info):
    """The case's camera, explicit: "default" is ParaView's reset camera (from +z, +y up, the bounding sphere
    filling the vertical view angle), the camera `uvr render` takes without --eye."""
    camera = case.get("camera", "default")
    if camera != "default":
        return {"eye": list(camera["eye"]), "at": list(camera["at"]), "up": list(camera["up"]),
                "fovy": float(camera.get("fovy", 30))}
    b = info["bounds"]
    at = [0.5 * (b[0] + b[1]), 0.5 * (b[2] + b[3]), 0.5 * (b[4] + b[5])]
    radius = 0.5 * math.sqrt((b[1] - b[0]) ** 2 + (b[3] - b[2]) ** 2 + (b[5] - b[4]) ** 2)
    fovy = 30.0
    distance = radius / math.sin(math.radians(0.5 * fovy))
    return {"eye": [at[0], at[1], at[2] + distance], "at": at, "up": [0.0, 1.0, 0.0], "fovy": fovy}


def camera_args(camera):
    def vec(v):
        return ",".join(repr(float(x)) for x in v)
    return ["--eye", vec(camera["eye"]), "--at", vec(camera["at"]), "--up", vec(camera["up"]),
            "--fovy", repr(float(camera["fovy"]))]


def render(uvr, mesh, stem, args):
    """`uvr render` to stem.png, stem_samples.png and stem.json; returns the stats."""
    run([uvr, "render", mesh, *args, "-o", stem + ".png", "--heatmap", stem + "_samples.png",
         "--stats", stem + ".json"])
    with open(stem + ".json") as f:
        return json.load(f)


def compare(uvr, a, b):
    """SSIM and PSNR of two PNGs by `uvr compare` (PSNR None for identical images)."""
    return json.loads(run([uvr, "compare", a, b, "--json"]))


def machine():
    model = platform.processor() or "unknown"
    try:
        with open("/proc/cpuinfo") as f:
            for line in f:
                if line.startswith("model name"):
                    model = line.split(":", 1)[1].strip()
                    break
    except OSError:
        pass
    try:
        with open("/proc/meminfo") as f:
            memory_gib = int(f.readline().split()[1]) / 2**20
    except (OSError, ValueError, IndexError):
        memory_gib = float("nan")
    return {"cpu": model, "cores": os.cpu_count(), "memory_gib": round(memory_gib, 1),
            "load_average": list(os.getloadavg())}


def montage(paths, labels, out, thumb):
    """Thumbnails of `paths` side by side with a label above each, as one PNG."""
    from PIL import Image, ImageDraw
    images = []
    for path in paths:
        image = Image.open(path).convert("RGB")
        scale = thumb / max(image.size)
        if scale < 1:
            image = image.resize((max(1, round(image.width * scale)), max(1, round(image.height * scale))),
                                 Image.LANCZOS)
        images.append(image)
    label_height = 14
    width = sum(i.width for i in images) + 4 * (len(images) - 1)
    height = max(i.height for i in images) + label_height
    sheet = Image.new("RGB", (width, height), (255, 255, 255))
    draw = ImageDraw.Draw(sheet)
    x = 0
    for image, label in zip(images, labels):
        sheet.paste(image, (x, label_height))
        draw.text((x + 2, 1), label, fill=(0, 0, 0))
        x += image.width + 4
    sheet.save(out, optimize=True)


def median(values):
    return statistics.median(values)


def fmt(value, digits=1):
    if value is None:
        return "–"
    if isinstance(value, float) and math.isinf(value):
        return "∞"
    return f"{value:.{digits}f}"
