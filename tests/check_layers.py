#!/usr/bin/env python3
"""Checks the layering of uvr's sources by their #include lines; exits 1 listing every violation.

- src/: one layer per directory, in the order of LAYERS; a file may include the internal headers of its own
  layer and of the layers below, not those of a layer above nor of another layer of the same rank, and any
  public header <uvr/...>.
- include/uvr/ (the public API): only other <uvr/...> headers and the standard library.
- The front ends (apps/, python/, the VTK mapper in vtk/, the ParaView plugin in paraview/): <uvr/...>, their
  own headers (under apps/ and vtk/) and third-party libraries; no internal header.

Usage: check_layers.py SOURCE_DIR
"""
import os
import re
import sys
import tempfile

# Lowest first; the layers of one tuple share a rank and do not include each other.
LAYERS = ["core", "mesh", ("io", "accel", "image", "gen"), "render", "backend", "engine", "api"]

# Violations tolerated for now. An entry that no longer occurs is reported too, so that the list only shrinks.
KNOWN = set()

INCLUDE = re.compile(r'^\s*#\s*include\s*([<"])([^>"]+)[>"]', re.MULTILINE)
SOURCE_SUFFIXES = (".h", ".hpp", ".cpp", ".cxx", ".cu", ".cuh")


def ranks():
    result = {}
    for rank, layer in enumerate(LAYERS):
        for name in layer if isinstance(layer, tuple) else (layer,):
            result[name] = rank
    return result


def sources(root):
    for directory, _, files in os.walk(root):
        for name in sorted(files):
            if name.endswith(SOURCE_SUFFIXES):
                yield os.path.join(directory, name)


def includes(path):
    with open(path, encoding="utf-8", errors="replace") as f:
        return INCLUDE.findall(f.read())


def is_standard(header):
    # <cmath>, <span>, <string>: the C++ standard library names its headers without an extension or a path.
    return "." not in header and "/" not in header


def check(top):
    """The violations under the source tree `top`, as (file, included header, why) with file relative to it."""
    layer_rank = ranks()
    src, public, apps = (os.path.join(top, d) for d in ("src", "include", "apps"))
    found = []

    def public_header(header):
        return header.startswith("uvr/") and os.path.isfile(os.path.join(public, header))

    def internal_header(header):
        return os.path.isfile(os.path.join(src, header))

    for path in sources(src):
        rel = os.path.relpath(path, top)
        layer = os.path.relpath(path, src).split(os.sep)[0]
        if layer not in layer_rank:
            found.append((rel, "", f"src/{layer} is in no layer: add it to LAYERS in tests/check_layers.py"))
            continue
        for kind, header in includes(path):
            if kind == "<":
                if header.startswith("uvr/") and not public_header(header):
                    found.append((rel, header, "no such public header"))
                elif not header.startswith("uvr/") and internal_header(header):
                    found.append((rel, header, "internal headers are included with quotes"))
                continue
            if not internal_header(header):
                found.append((rel, header, "not a header under src/"))
                continue
            target = header.split("/")[0]
            if target not in layer_rank:
                found.append((rel, header, f"src/{target} is in no layer"))
            elif layer_rank[target] > layer_rank[layer]:
                found.append((rel, header, f"upward: {layer} includes {target}"))
            elif layer_rank[target] == layer_rank[layer] and target != layer:
                found.append((rel, header, f"sideways: {layer} and {target} are layers of one rank"))

    for path in sources(os.path.join(public, "uvr")):
        rel = os.path.relpath(path, top)
        for kind, header in includes(path):
            if kind == "<" and (public_header(header) or is_standard(header)):
                continue
            found.append((rel, header, "a public header includes only <uvr/...> and the standard library"))

    front_ends = [apps] + [os.path.join(top, d) for d in ("python", "vtk", "paraview")]
    for front_end in front_ends:
        for path in sources(front_end):
            rel = os.path.relpath(path, top)
            own = [os.path.dirname(path), os.path.join(top, "vtk")] + [os.path.join(apps, d) for d in
                                                                      sorted(os.listdir(apps))]
            for kind, header in includes(path):
                if header.startswith("uvr/"):
                    if kind == '"' or not public_header(header):
                        found.append((rel, header, "the public headers are included as <uvr/...>"))
                elif kind == '"' and any(os.path.isfile(os.path.join(d, header)) for d in own):
                    continue
                elif internal_header(header):
                    found.append((rel, header, "a front end includes only <uvr/...>, not the internals"))
                elif kind == '"':
                    found.append((rel, header, "not a header of the front ends"))
    return found


def self_test():
    """The check finds what it is for: an upward, a sideways and a front end's internal include."""
    files = {
        "src/core/a.h": '#include "mesh/b.h"\n',
        "src/mesh/b.h": '#include "core/a.h"\n#include <uvr/p.h>\n',
        "src/io/c.h": '#include "gen/d.h"\n',
        "src/gen/d.h": "",
        "include/uvr/p.h": "#include <vector>\n#include <tbb/tbb.h>\n",
        "apps/x/main.cpp": '#include "mesh/b.h"\n#include <uvr/p.h>\n#include "own.h"\n',
        "apps/x/own.h": "",
        "vtk/m.cxx": '#include "mesh/b.h"\n#include <vtkObject.h>\n#include "m.h"\n',
        "vtk/m.h": "",
    }
    with tempfile.TemporaryDirectory() as top:
        for name, text in files.items():
            os.makedirs(os.path.dirname(os.path.join(top, name)), exist_ok=True)
            with open(os.path.join(top, name), "w") as f:
                f.write(text)
        got = {(f, h) for f, h, _ in check(top)}
    expected = {("src/core/a.h", "mesh/b.h"), ("src/io/c.h", "gen/d.h"), ("include/uvr/p.h", "tbb/tbb.h"),
                ("apps/x/main.cpp", "mesh/b.h"), ("vtk/m.cxx", "mesh/b.h")}
    if got != expected:
        sys.exit(f"check_layers.py: the self-test found {sorted(got)}, expected {sorted(expected)}")


def main():
    if len(sys.argv) != 2:
        sys.exit(__doc__)
    self_test()
    found = check(sys.argv[1])
    failures = [(f, h, why) for f, h, why in found if (f, h) not in KNOWN]
    seen = {(f, h) for f, h, _ in found}
    failures += [(f, h, "listed in KNOWN but no longer included: remove it from KNOWN") for f, h in
                 sorted(KNOWN - seen)]
    for f, h, why in failures:
        print(f"{f}: {h}: {why}")
    known = sorted(KNOWN & seen)
    if known:
        print(f"({len(known)} known violation(s) left, being removed: " +
              ", ".join(f"{f} includes {h}" for f, h in known) + ")")
    sys.exit(1 if failures else 0)


if __name__ == "__main__":
    main()
