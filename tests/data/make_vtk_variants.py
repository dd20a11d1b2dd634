#!/usr/bin/python3
"""Writes tests/data/vtk: the small real files of ../shared/data/small re-encoded by VTK's own writers in
every encoding the readers support, plus one reference reading per group of variants.

Needs Debian's python3-vtk9 (VTK 9.1): run with /usr/bin/python3 from the repository root:
    /usr/bin/python3 tests/data/make_vtk_variants.py [shared-data-dir]

A file is named <group>__<variant>.vtu|.vtk; every file of a group reads (by VTK) exactly as <group>.ref.txt
says, which the script checks before it writes the reference.
"""
import math
import os
import sys

from vtkmodules.vtkCommonCore import (vtkDoubleArray, vtkFloatArray, vtkIdList, vtkIntArray, vtkLongLongArray,
                                      vtkPoints, vtkShortArray, vtkSignedCharArray, vtkUnsignedCharArray,
                                      vtkUnsignedIntArray, vtkUnsignedLongLongArray, vtkUnsignedShortArray,
                                      vtkVersion)
from vtkmodules.vtkCommonDataModel import vtkUnstructuredGrid
from vtkmodules.vtkFiltersParallel import vtkExtractUnstructuredGridPiece
from vtkmodules.vtkIOLegacy import vtkUnstructuredGridReader, vtkUnstructuredGridWriter
from vtkmodules.vtkIOXML import vtkXMLUnstructuredGridReader, vtkXMLUnstructuredGridWriter

ROOT = os.path.dirname(os.path.abspath(__file__))
SHARED = sys.argv[1] if len(sys.argv) > 1 else os.path.join(ROOT, '..', '..', '..', 'shared', 'data')
OUT = os.path.join(ROOT, 'vtk')


def read(path):
    reader = vtkXMLUnstructuredGridReader() if path.endswith('.vtu') else vtkUnstructuredGridReader()
    reader.SetFileName(path)
    reader.Update()
    grid = vtkUnstructuredGrid()
    grid.DeepCopy(reader.GetOutput())
    return grid


def describe(grid):
    """The reference reading: points, cells and every numeric point/cell array as one value per tuple
    (the Euclidean magnitude when it has several components)."""
    lines = ['points %d' % grid.GetNumberOfPoints()]
    for i in range(grid.GetNumberOfPoints()):
        lines.append('%.9g %.9g %.9g' % grid.GetPoint(i))
    lines.append('cells %d' % grid.GetNumberOfCells())
    ids = vtkIdList()
    for i in range(grid.GetNumberOfCells()):
        grid.GetCellPoints(i, ids)
        lines.append(' '.join(str(v) for v in [grid.GetCellType(i), ids.GetNumberOfIds()] +
                              [ids.GetId(k) for k in range(ids.GetNumberOfIds())]))
    for centering, data in (('point', grid.GetPointData()), ('cell', grid.GetCellData())):
        # By name: the legacy writer puts attributes (SCALARS, VECTORS) before other arrays.
        arrays = [data.GetArray(a) for a in range(data.GetNumberOfArrays())]
        for array in sorted((a for a in arrays if a is not None), key=lambda a: a.GetName()):  # None: strings
            values = [math.sqrt(sum(float(c) ** 2 for c in array.GetTuple(t)))
                      if array.GetNumberOfComponents() > 1 else array.GetTuple(t)[0]
                      for t in range(array.GetNumberOfTuples())]
            lines.append('field %s %s %d' % (centering, array.GetName(), len(values)))
            lines.append(' '.join('%.9g' % v for v in values))
    return '\n'.join(lines) + '\n'


def write_xml(grid, name, mode, compressor='zlib', header=64, ids=64, big_endian=False, encode=False,
              pieces=1):
    writer = vtkXMLUnstructuredGridWriter()
    if pieces > 1:
        # The writer asks its input for each piece: a piece filter splits the grid.
        splitter = vtkExtractUnstructuredGridPiece()
        splitter.SetInputData(grid)
        writer.SetInputConnection(splitter.GetOutputPort())
        writer.SetNumberOfPieces(pieces)
    else:
        writer.SetInputData(grid)
    writer.SetFileName(os.path.join(OUT, name))
    {'ascii': writer.SetDataModeToAscii, 'binary': writer.SetDataModeToBinary,
     'appended': writer.SetDataModeToAppended}[mode]()
    writer.SetEncodeAppendedData(1 if encode else 0)
    writer.SetCompressorTypeToZLib() if compressor == 'zlib' else writer.SetCompressorTypeToNone()
    writer.SetHeaderTypeToUInt64() if header == 64 else writer.SetHeaderTypeToUInt32()
    writer.SetIdTypeToInt64() if ids == 64 else writer.SetIdTypeToInt32()
    writer.SetByteOrderToBigEndian() if big_endian else writer.SetByteOrderToLittleEndian()
    assert writer.Write() == 1, name
    return name


def write_legacy(grid, name, binary, version):
    writer = vtkUnstructuredGridWriter()
    writer.SetInputData(grid)
    writer.SetFileName(os.path.join(OUT, name))
    writer.SetFileVersion(version)
    writer.SetFileTypeToBinary() if binary else writer.SetFileTypeToASCII()
    assert writer.Write() == 1, name
    return name


def with_double_points(grid):
    copy = vtkUnstructuredGrid()
    copy.DeepCopy(grid)
    points = vtkPoints()
    points.SetDataTypeToDouble()
    points.SetNumberOfPoints(grid.GetNumberOfPoints())
    for i in range(grid.GetNumberOfPoints()):
        points.SetPoint(i, grid.GetPoint(i))
    copy.SetPoints(points)
    return copy


def with_typed_arrays(grid):
    """One cell array per VTK scalar type, values from the cell index spread over the type's range."""
    copy = vtkUnstructuredGrid()
    copy.DeepCopy(grid)
    types = [('int8', vtkSignedCharArray, True, 1), ('uint8', vtkUnsignedCharArray, False, 1),
             ('int16', vtkShortArray, True, 200), ('uint16', vtkUnsignedShortArray, False, 200),
             ('int32', vtkIntArray, True, 10**7), ('uint32', vtkUnsignedIntArray, False, 10**7),
             ('int64', vtkLongLongArray, True, 10**15), ('uint64', vtkUnsignedLongLongArray, False, 10**15),
             ('float32', vtkFloatArray, True, 0.5), ('float64', vtkDoubleArray, True, 1e-3)]
    for name, cls, signed, scale in types:
        array = cls()
        array.SetName('id_' + name)
        for i in range(copy.GetNumberOfCells()):
            array.InsertNextValue(((i * 37) % 256 - (128 if signed else 0)) * scale)
        copy.GetCellData().AddArray(array)
    return copy


def with_metadata(grid):
    """Component names and a computed norm range make the legacy writer emit METADATA blocks."""
    copy = vtkUnstructuredGrid()
    copy.DeepCopy(grid)
    velocity = copy.GetPointData().GetArray('velocity')
    velocity.SetComponentName(0, 'vx')
    velocity.SetComponentName(2, 'v z')
    velocity.GetRange(-1)
    copy.GetPoints().GetData().GetRange(-1)
    return copy


def main():
    os.makedirs(OUT, exist_ok=True)
    small = os.path.join(SHARED, 'small')
    ugrid = read(os.path.join(small, 'uGridEx.vtk'))
    field = read(os.path.join(small, 'fieldfile.vtk'))
    sfepy = read(os.path.join(small, 'sfepy_cylinder.vtk'))
    pyramid = read(os.path.join(small, 'pyramid_ug.vtu'))
    typed = with_typed_arrays(ugrid)

    groups = {
        'uGridEx': (ugrid, [
            write_xml(ugrid, 'uGridEx__ascii.vtu', 'ascii'),
            write_xml(ugrid, 'uGridEx__binary_zlib_h32_id32.vtu', 'binary', 'zlib', 32, 32),
            write_xml(ugrid, 'uGridEx__binary_none_h64.vtu', 'binary', 'none', 64),
            write_xml(ugrid, 'uGridEx__appended_raw_zlib_h64.vtu', 'appended', 'zlib', 64),
            write_xml(ugrid, 'uGridEx__appended_raw_none_h32_id32.vtu', 'appended', 'none', 32, 32),
            write_xml(ugrid, 'uGridEx__appended_base64_zlib_h32.vtu', 'appended', 'zlib', 32, encode=True),
            write_xml(ugrid, 'uGridEx__appended_base64_none_h64.vtu', 'appended', 'none', 64, encode=True),
            write_xml(ugrid, 'uGridEx__bigendian_appended_raw_zlib_h64.vtu', 'appended', 'zlib', 64,
                      big_endian=True),
            write_xml(ugrid, 'uGridEx__bigendian_binary_none_h32.vtu', 'binary', 'none', 32, big_endian=True),
            write_legacy(ugrid, 'uGridEx__ascii_v42.vtk', False, 42),
            write_legacy(ugrid, 'uGridEx__ascii_v51.vtk', False, 51),
            write_legacy(ugrid, 'uGridEx__binary_v42.vtk', True, 42),
            write_legacy(ugrid, 'uGridEx__binary_v51.vtk', True, 51),
        ]),
        'fieldfile': (field, [
            write_xml(field, 'fieldfile__ascii.vtu', 'ascii'),
            write_xml(field, 'fieldfile__appended_base64_zlib_h64.vtu', 'appended', 'zlib', 64, encode=True),
            write_legacy(field, 'fieldfile__ascii_v51.vtk', False, 51),
            write_legacy(field, 'fieldfile__binary_v42.vtk', True, 42),
            write_legacy(field, 'fieldfile__binary_v51.vtk', True, 51),
        ]),
        'sfepy': (sfepy, [
            write_xml(sfepy, 'sfepy__appended_raw_zlib_h64.vtu', 'appended', 'zlib', 64),
            write_xml(with_double_points(sfepy), 'sfepy__float64_points_binary_zlib_h32.vtu', 'binary', 'zlib', 32),
            write_legacy(sfepy, 'sfepy__binary_v51.vtk', True, 51),
            write_legacy(with_double_points(sfepy), 'sfepy__float64_points_binary_v42.vtk', True, 42),
        ]),
        'uGridEx_typed': (typed, [
            write_xml(typed, 'uGridEx_typed__ascii.vtu', 'ascii'),
            write_xml(typed, 'uGridEx_typed__appended_raw_none_h64.vtu', 'appended', 'none', 64),
            write_xml(typed, 'uGridEx_typed__bigendian_appended_base64_zlib_h32.vtu', 'appended', 'zlib', 32,
                      big_endian=True, encode=True),
            write_legacy(typed, 'uGridEx_typed__ascii_v42.vtk', False, 42),
            write_legacy(typed, 'uGridEx_typed__binary_v51.vtk', True, 51),
        ]),
        'pyramid': (pyramid, [
            write_xml(pyramid, 'pyramid__binary_zlib_h64.vtu', 'binary', 'zlib', 64),
            write_legacy(pyramid, 'pyramid__ascii_v51.vtk', False, 51),
            write_legacy(with_metadata(pyramid), 'pyramid__metadata_ascii_v51.vtk', False, 51),
            write_legacy(with_metadata(pyramid), 'pyramid__metadata_binary_v51.vtk', True, 51),
        ]),
    }
    # Several <Piece>s: VTK's reader merges them, and that merged grid is the reference.
    pieces = write_xml(sfepy, 'sfepy_pieces__3pieces_appended_raw_zlib_h64.vtu', 'appended', 'zlib', 64,
                       pieces=3)
    groups['sfepy_pieces'] = (read(os.path.join(OUT, pieces)), [pieces])

    for group, (grid, files) in groups.items():
        reference = describe(grid)
        for name in files:
            assert describe(read(os.path.join(OUT, name))) == reference, name
            assert os.path.getsize(os.path.join(OUT, name)) < 100_000, name
        with open(os.path.join(OUT, group + '.ref.txt'), 'w') as f:
            f.write('# %s: VTK %s reading, one line per point, cell (type count ids) and field\n' %
                    (group, vtkVersion.GetVTKVersion()))
            f.write(reference)


if __name__ == '__main__':
    main()
