#!/usr/bin/python3
"""Malformed mesh files, each a real file of ../shared/data (or a CDL test mesh) altered one way, with the
substring the reader's error must contain.

    tests/malformed_corpus.py SHARED_DATA OUT_DIR    writes the corpus and OUT_DIR/expected.tsv

test_malformed_corpus.py runs `uvr info` and `uvr render` on each; scripts/fuzz seeds the fuzzers with them.
"""
import base64
import os
import re
import shutil
import struct
import subprocess
import sys
import zlib

HERE = os.path.dirname(os.path.abspath(__file__))
CDL = os.path.join(HERE, "data", "exodus")


class Corpus:
    def __init__(self, shared, out):
        self.shared, self.out = shared, out
        self.cases = []  # (file name, expected error substring)

    def read(self, relative):
        with open(os.path.join(self.shared, relative), "rb") as f:
            return f.read()

    def add(self, name, data, expected):
        with open(os.path.join(self.out, name), "wb") as f:
            f.write(data)
        self.cases.append((name, expected))

    def edit(self, name, data, old, new, expected, count=1):
        """`data` with its first `count` occurrences of `old` replaced by `new`."""
        if old not in data:
            raise ValueError(f"{name}: {old!r} not in the source")
        self.add(name, data.replace(old, new, count), expected)


# Legacy .vtk text files.

def legacy_cases(c):
    grid = c.read("small/uGridEx.vtk")  # ASCII, 27 points, 12 cells of 7 types, point data
    size = len(grid)
    c.add("legacy_cut_header.vtk", grid[:30], "expected 'ASCII' or 'BINARY'")
    c.add("legacy_cut_points.vtk", grid[:grid.index(b"POINTS") + 60], "the file ends")
    c.add("legacy_cut_cells.vtk", grid[:grid.index(b"CELLS") + 40], "the file ends")
    c.add("legacy_cut_types.vtk", grid[:grid.index(b"CELL_TYPES") + 20], "the file ends")
    c.add("legacy_cut_point_data.vtk", grid[:size - 20], "the file ends")
    c.edit("legacy_points_huge.vtk", grid, b"POINTS 27", b"POINTS 2700000000000", "declared but the file ends")
    c.edit("legacy_points_negative.vtk", grid, b"POINTS 27", b"POINTS -27", "expected 'POINTS n type'")
    c.edit("legacy_cells_huge.vtk", grid, b"CELLS 12 63", b"CELLS 12 63000000000", "declared but the file ends")
    c.edit("legacy_cells_negative.vtk", grid, b"CELLS 12 63", b"CELLS -12 63", "expected 'CELLS n size'")
    c.edit("legacy_cell_count_past_size.vtk", grid, b"CELLS 12 63", b"CELLS 64 63", "cannot fit in 63 values")
    c.edit("legacy_cell_runs_past.vtk", grid, b"\n1 25\n", b"\n9 25\n", "runs past the CELLS size")
    c.edit("legacy_index_high.vtk", grid, b"8 0 1 4 3 6 7 10 9", b"8 0 1 4 3 6 7 10 999",
           "point index 999 at entry 7 is outside [0, 27)")
    c.edit("legacy_index_negative.vtk", grid, b"4 7 10 9 12", b"4 7 10 -9 12", "point index -9")
    c.edit("legacy_unknown_type.vtk", grid, b"CELL_TYPES 12\n12\n12\n10", b"CELL_TYPES 12\n12\n12\n99",
           "unsupported VTK cell type 99")
    c.edit("legacy_type_not_a_byte.vtk", grid, b"CELL_TYPES 12\n12", b"CELL_TYPES 12\n300",
           "cell type 300 is not a VTK type code")
    c.edit("legacy_type_count.vtk", grid, b"CELL_TYPES 12\n12\n", b"CELL_TYPES 11\n", "CELL_TYPES lists 11")
    c.edit("legacy_nan_point.vtk", grid, b"POINTS 27 float\n0.0 0.0 0.0", b"POINTS 27 float\n0.0 nan 0.0",
           "point 0 is not finite")
    c.edit("legacy_inf_point.vtk", grid, b"1.0 0.0 0.0", b"1.0 -inf 0.0", "point 1 is not finite")
    c.edit("legacy_bad_number.vtk", grid, b"2.0 0.0 0.0", b"2.0 0.0x 0.0", "invalid number '0.0x'")
    c.edit("legacy_polydata.vtk", grid, b"UNSTRUCTURED_GRID", b"POLYDATA", "unsupported dataset type")
    c.edit("legacy_point_data_count.vtk", grid, b"POINT_DATA 27", b"POINT_DATA 28", "differs from the point count")
    c.edit("legacy_data_type.vtk", grid, b"SCALARS scalars float", b"SCALARS scalars floot",
           "unknown data type 'floot'")
    c.edit("legacy_not_vtk.vtk", grid, b"# vtk DataFile", b"# xyz DataFile", "expected '# vtk DataFile")

    # Cell data in FIELD arrays, and tets with a cell field.
    fields = c.read("small/fieldfile.vtk")
    c.edit("legacy_field_tuples.vtk", fields, b"group 1 3 int", b"group 1 2 int", "has 2 tuples, expected 3")
    c.edit("legacy_field_arrays.vtk", fields, b"FIELD attributes 3", b"FIELD attributes 9",
           "expected 9 FIELD arrays")
    c.edit("legacy_cell_data_count.vtk", fields, b"CELL_DATA 3", b"CELL_DATA 4", "differs from the cell count")
    cylinder = c.read("small/sfepy_cylinder.vtk")
    c.add("legacy_cylinder_cut_half.vtk", cylinder[:len(cylinder) // 2], "the file ends")
    c.edit("legacy_cylinder_cell_count.vtk", cylinder, b"CELLS 1348", b"CELLS 1349", "runs past the CELLS size")

    # The same tets as big-endian BINARY (VTK 4.2 layout): binary data has no lines, so errors give bytes.
    binary = to_binary_legacy(cylinder)
    c.add("binary_cut_points.vtk", binary[:binary.index(b"POINTS") + 300], "the file ends before them")
    points = binary.index(b"\n", binary.index(b"POINTS")) + 1
    c.add("binary_nan_point.vtk", binary[:points + 4] + struct.pack(">f", float("nan")) + binary[points + 8:],
          "point 0 is not finite")
    cells = binary.index(b"\n", binary.index(b"CELLS")) + 1
    c.add("binary_index_high.vtk", binary[:cells + 4] + struct.pack(">i", 354) + binary[cells + 8:],
          "point index 354 at entry 0 is outside [0, 354)")
    c.add("binary_vertex_count.vtk", binary[:cells] + struct.pack(">i", -4) + binary[cells + 4:],
          "cell 0 runs past the CELLS size")
    types = binary.index(b"\n", binary.index(b"CELL_TYPES")) + 1
    # 15, VTK's pentagonal prism: a volume cell uvr does not take (42, the polyhedron, it does).
    c.add("binary_unknown_type.vtk", binary[:types] + struct.pack(">i", 15) + binary[types + 4:],
          "unsupported VTK cell type 15")


def to_binary_legacy(text):
    """An ASCII legacy file with POINTS float, CELLS, CELL_TYPES and CELL_DATA SCALARS int, as BINARY."""
    lines = text.decode().split("\n")
    out, i = [], 0
    words = lambda: [w for l in lines[i + 1:] for w in l.split()]
    while i < len(lines):
        line = lines[i]
        head = line.split()
        if line.strip() == "ASCII":
            out.append(b"BINARY\n")
        elif head and head[0] in ("POINTS", "CELLS", "CELL_TYPES") or head[:1] == ["LOOKUP_TABLE"]:
            if head[0] == "POINTS":
                n, fmt = 3 * int(head[1]), ">f"
            elif head[0] == "CELLS":
                n, fmt = int(head[2]), ">i"
            elif head[0] == "CELL_TYPES":
                n, fmt = int(head[1]), ">i"
            else:
                n, fmt = cell_data_count, ">i"
            values = words()[:n]
            out.append(line.encode() + b"\n")
            out.append(b"".join(struct.pack(fmt, float(v) if fmt == ">f" else int(v)) for v in values) + b"\n")
            taken = 0
            while taken < n:  # skip the text lines the values came from
                i += 1
                taken += len(lines[i].split())
        else:
            if head[:1] == ["CELL_DATA"]:
                cell_data_count = int(head[1])
            out.append(line.encode() + b"\n")
        i += 1
    return b"".join(out).rstrip(b"\n") + b"\n"


# XML .vtu files: appended arrays are decoded, altered and encoded again.

def parse_appended(data):
    """(head, arrays by name, encoding, header format) of an appended, zlib-compressed .vtu."""
    marker = data.index(b"_", data.index(b"<AppendedData")) + 1
    head, payload = data[:marker], data[marker:]
    encoding = re.search(rb'<AppendedData encoding="(\w+)"', data).group(1).decode()
    word = "<Q" if b'header_type="UInt64"' in head else "<I"
    arrays = {}
    for m in re.finditer(rb'<DataArray[^>]*Name="([^"]*)"[^>]*offset="(\d+)', head):
        arrays[m.group(1).decode()] = decode_array(payload, int(m.group(2)), encoding, word)
    return head, arrays, encoding, word


def decode_array(payload, offset, encoding, word):
    size = struct.calcsize(word)
    if encoding == "raw":
        count = struct.unpack_from(word, payload, offset)[0]
        header = struct.unpack_from(word[0] + word[1] * (3 + count), payload, offset)
        start = offset + size * (3 + count)
        blocks, at = [], start
        for s in header[3:]:
            blocks.append(zlib.decompress(payload[at:at + s]))
            at += s
        return b"".join(blocks)
    first = base64.b64decode(payload[offset:offset + 8])  # the block count
    count = struct.unpack_from(word, first)[0]
    header_chars = (size * (3 + count) + 2) // 3 * 4
    header = struct.unpack(word[0] + word[1] * (3 + count), base64.b64decode(payload[offset:offset + header_chars]))
    data_chars = (sum(header[3:]) + 2) // 3 * 4
    compressed = base64.b64decode(payload[offset + header_chars:offset + header_chars + data_chars])
    blocks, at = [], 0
    for s in header[3:]:
        blocks.append(zlib.decompress(compressed[at:at + s]))
        at += s
    return b"".join(blocks)


def encode_vtu(head, arrays, encoding, word, header_override=None):
    """Writes the arrays again, one zlib block each, in the head's order, with fresh offsets."""
    payload, offsets = b"", {}
    for m in re.finditer(rb'<DataArray[^>]*Name="([^"]*)"[^>]*offset="(\d+)', head):
        name = m.group(1).decode()
        raw = arrays[name]
        compressed = zlib.compress(raw)
        header = [1, max(len(raw), 1), len(raw), len(compressed)]
        if header_override and name in header_override:
            header = header_override[name](header)
        header_bytes = struct.pack(word[0] + word[1] * len(header), *header)
        offsets[name] = len(payload)
        if encoding == "raw":
            payload += header_bytes + compressed
        else:
            payload += base64.b64encode(header_bytes) + base64.b64encode(compressed)

    def set_offset(m):
        name = re.search(rb'Name="([^"]*)"', m.group(0)).group(1).decode()
        return re.sub(rb'offset="\d+"', b'offset="%d"' % offsets[name], m.group(0))

    head = re.sub(rb'<DataArray[^>]*Name="[^"]*"[^>]*offset="\d+"', set_offset, head)
    tail = b"\n  </AppendedData>\n</VTKFile>\n"
    return head + payload + tail


def vtu_cases(c):
    pyramid = c.read("small/pyramid_ug.vtu")  # appended base64, zlib, UInt32 headers
    head, arrays, encoding, word = parse_appended(pyramid)
    assert encode_vtu(head, arrays, encoding, word).startswith(head[:200])

    def altered(name, array, transform, expected, source=(head, arrays, encoding, word), override=None):
        h, a, e, w = source
        changed = dict(a)
        if array:
            changed[array] = transform(bytearray(a[array]))
        c.add(name, encode_vtu(h, changed, e, w, override), expected)

    def put(fmt, index, value):
        def transform(b):
            struct.pack_into(fmt, b, index * struct.calcsize(fmt), value)
            return bytes(b)
        return transform

    marker = pyramid.index(b"_", pyramid.index(b"<AppendedData")) + 1
    c.add("vtu_cut_appended.vtu", pyramid[:marker + 200], "ends")
    c.add("vtu_cut_xml.vtu", pyramid[:pyramid.index(b"<Cells>")], "malformed XML")
    c.add("vtu_cut_marker.vtu", pyramid[:marker - 1], "expected '_' at the start of the appended data")
    bad = bytearray(pyramid)
    bad[marker + 40] = ord("!")
    c.add("vtu_bad_base64.vtu", bytes(bad), "invalid base64 character")
    c.edit("vtu_header_type.vtu", pyramid, b'byte_order="LittleEndian"',
           b'byte_order="LittleEndian" header_type="UInt16"', "unsupported header_type 'UInt16'")
    c.edit("vtu_header_type_wrong.vtu", pyramid, b'byte_order="LittleEndian"',
           b'byte_order="LittleEndian" header_type="UInt64"', "compressed blocks declared but the file ends first")
    c.edit("vtu_broken_xml.vtu", pyramid, b"</Piece>", b"</Peace>", "malformed XML")
    c.edit("vtu_points_huge.vtu", pyramid, b'NumberOfPoints="5"', b'NumberOfPoints="5000000000"',
           "inflates to 60 bytes, expected 60000000000")
    c.edit("vtu_points_negative.vtu", pyramid, b'NumberOfPoints="5"', b'NumberOfPoints="-5"',
           "expected a non-negative integer NumberOfPoints")
    c.edit("vtu_offset_past_end.vtu", pyramid, b'offset="328"', b'offset="99999999"', "is past the end of the file")
    c.edit("vtu_unknown_scalar_type.vtu", pyramid, b'type="Float32" Name="pressure"',
           b'type="Float128" Name="pressure"', "unsupported type 'Float128'")
    c.edit("vtu_compressor.vtu", pyramid, b"vtkZLibDataCompressor", b"vtkLZMADataCompressor", "unsupported compressor")
    c.edit("vtu_components.vtu", pyramid, b'NumberOfComponents="3" format="appended" offset="176"',
           b'NumberOfComponents="0" format="appended" offset="176"', "NumberOfComponents must be in")
    c.edit("vtu_not_unstructured.vtu", pyramid, b'type="UnstructuredGrid"', b'type="PolyData"',
           "unsupported dataset type 'PolyData'")
    altered("vtu_index_high.vtu", "connectivity", put("<i", 4, 99), "point index 99 at entry 4 is outside [0, 5)")
    altered("vtu_index_negative.vtu", "connectivity", put("<i", 0, -1), "point index -1 at entry 0")
    altered("vtu_unknown_type.vtu", "types", put("<B", 0, 99), "unsupported VTK cell type 99")
    altered("vtu_nan_point.vtu", "Array 0x9f3b340", put("<f", 4, float("nan")), "point 1 is not finite")
    altered("vtu_inf_point.vtu", "Array 0x9f3b340", put("<f", 0, float("inf")), "point 0 is not finite")
    altered("vtu_too_few_points.vtu", "offsets", put("<i", 0, 4), "inflates to 20 bytes, expected 16")
    altered("vtu_block_count.vtu", None, None, "compressed blocks declared",
            override={"pressure": lambda h: [100000000] + h[1:]})
    altered("vtu_last_block.vtu", None, None, "last block size exceeds the block size",
            override={"offsets": lambda h: [h[0], h[1], h[1] + 1] + h[3:]})

    disk = c.read("medium/disk_out_ref.vtu")  # appended raw, zlib, UInt32 headers, Int64 connectivity
    dhead, darrays, dencoding, dword = parse_appended(disk)
    source = (dhead, darrays, dencoding, dword)
    altered("vtu_disk_offsets_decrease.vtu", "offsets", put("<q", 1, 3), "offsets decrease (or start below 0) at cell 1",
            source)
    altered("vtu_disk_index_high.vtu", "connectivity", put("<q", 100, 8499),
            "point index 8499 at entry 100 is outside [0, 8499)", source)
    altered("vtu_disk_type.vtu", "types", put("<B", 7000, 0), "unsupported VTK cell type 0", source)
    altered("vtu_disk_nan_point.vtu", "Points", put("<f", 3 * 8000 + 2, float("nan")),
            "point 8000 is not finite", source)
    altered("vtu_disk_block_size.vtu", None, None, "compressed block 0 has an impossible size", source,
            override={"Points": lambda h: h[:3] + [50]})
    dmarker = disk.index(b"_", disk.index(b"<AppendedData")) + 1
    c.add("vtu_disk_cut.vtu", disk[:dmarker + len(disk[dmarker:]) // 2], "is past the end of the file")
    c.add("vtu_disk_cut_in_array.vtu", disk[:dmarker + 224422 + 300], "but the file ends first")
    # Corrupt zlib: the first compressed bytes of Temp's first block, after its header of 3 + blocks words.
    temp = dmarker + int(re.search(rb'Name="Temp"[^>]*offset="(\d+)"', disk).group(1))
    temp += 4 * (3 + struct.unpack_from("<I", disk, temp)[0])
    broken = bytearray(disk)
    broken[temp] ^= 0xFF
    broken[temp + 1] ^= 0xFF
    c.add("vtu_disk_zlib.vtu", bytes(broken), "zlib block 0 is corrupt")


# ParaView collections: no nesting, so no recursion (a collection naming itself, or two naming each other).

def collection_cases(c):
    def collection(*files):
        sets = "".join(f'<DataSet timestep="0" file="{f}"/>' for f in files)
        return f'<?xml version="1.0"?>\n<VTKFile type="Collection"><Collection>{sets}</Collection></VTKFile>\n'.encode()
    c.add("pvd_self.pvd", collection("pvd_self.pvd"), "names another collection 'pvd_self.pvd'")
    c.add("pvd_cycle_a.pvd", collection("pvd_cycle_b.pvd"), "names another collection 'pvd_cycle_b.pvd'")
    c.add("pvd_cycle_b.pvd", collection("pvd_cycle_a.pvd"), "names another collection 'pvd_cycle_a.pvd'")


# Exodus II (netCDF).

def exodus_cases(c, ncgen):
    disk = c.read("medium/disk_out_ref.ex2")  # netCDF-3 classic
    c.add("exodus_cut_header.ex2", disk[:600], "not a readable netCDF file")
    c.add("exodus_cut_data.ex2", disk[:len(disk) // 2], "the header lays out 704396 bytes but the file has 352200")
    c.add("exodus_cut_last_bytes.ex2", disk[:-8], "but the file has 704392")
    c.add("exodus_not_netcdf.e", b"# vtk DataFile Version 2.0\n" + disk[27:4000], "not a readable netCDF file")
    # The header stores each dimension's name and length: enlarge num_nodes beyond the file.
    name = b"num_nodes\x00\x00\x00" + struct.pack(">i", 8499)
    c.edit("exodus_nodes_huge.ex2", disk, name, b"num_nodes\x00\x00\x00" + struct.pack(">i", 0x7FFFFFF0),
           "the header lays out 77309809184 bytes but the file has 704400")

    with open(os.path.join(CDL, "two_blocks.cdl")) as f:
        cdl = f.read()

    def cdl_case(name, old, new, expected, kind="nc3", count=1):
        if old not in cdl:
            raise ValueError(f"{name}: {old!r} not in two_blocks.cdl")
        text = cdl.replace(old, new, count)
        source = os.path.join(c.out, name + ".cdl")
        with open(source, "w") as f:
            f.write(text)
        subprocess.run([ncgen, "-k", kind, "-o", os.path.join(c.out, name), source], check=True)
        os.remove(source)
        c.cases.append((name, expected))

    cdl_case("exodus_index_high.e", "connect2 =\n  2, 9, 10", "connect2 =\n  2, 99, 10",
             "element 1 refers to node 99, outside [1, 20]")
    cdl_case("exodus_index_zero.exo", "connect1 =\n  1, 2", "connect1 =\n  0, 2",
             "element 1 refers to node 0, outside [1, 20]")
    cdl_case("exodus_nan_coordinate.e", "coordy = 0, 0", "coordy = 0, NaN", "coordinate of node 2 is not finite")
    cdl_case("exodus_inf_coordinate.g", "coordz = 0, 0", "coordz = Infinity, 0", "coordinate of node 1 is not finite")
    cdl_case("exodus_no_coordinates.e", "coordx", "coordw", "no coordinates", count=2)
    cdl_case("exodus_no_elem_type.e", 'connect1:elem_type = "HEX8" ;', 'connect1:type = "HEX8" ;',
             "expected a text attribute 'elem_type'")
    cdl_case("exodus_too_few_nodes.e", "num_nod_per_el3 = 5 ;", "num_nod_per_el3 = 4 ;",
             "PYRAMID5 elements need at least 5 nodes", "nc3")
    cdl_case("exodus_field_shape.e", "double vals_nod_var2(time_step, num_nodes) ;",
             "double vals_nod_var2(time_step, num_elem) ;", "variable 'vals_nod_var2': has shape (10, 6), expected (10, 20)")
    cdl_case("exodus_index_high_nc4.e", "connect2 =\n  2, 9, 10", "connect2 =\n  2, 99, 10",
             "element 1 refers to node 99", "nc4")
    nc4 = os.path.join(c.out, "exodus_index_high_nc4.e")
    with open(nc4, "rb") as f:
        whole = f.read()
    c.add("exodus_nc4_cut.e", whole[:len(whole) // 2], "not a readable netCDF file")


def generate(shared, out, ncgen=None):
    """Writes the corpus into `out`; returns [(file name, expected substring)]."""
    os.makedirs(out, exist_ok=True)
    c = Corpus(shared, out)
    legacy_cases(c)
    vtu_cases(c)
    collection_cases(c)
    ncgen = ncgen or shutil.which("ncgen")
    if ncgen:
        exodus_cases(c, ncgen)
    with open(os.path.join(out, "expected.tsv"), "w") as f:
        for name, expected in c.cases:
            f.write(f"{name}\t{expected}\n")
    return c.cases


if __name__ == "__main__":
    if len(sys.argv) != 3:
        sys.exit(__doc__)
    print(f"{len(generate(sys.argv[1], sys.argv[2]))} malformed files in {sys.argv[2]}")
