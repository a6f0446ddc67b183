#!/usr/bin/env python3
"""Read loam's binary VTU frames with VTK's own reader and compare them with ASCII frames
of the same run.

For each points_NNNNN.vtu of ASCII_DIR, the frame of the same name in BINARY_DIR is read by
vtkXMLUnstructuredGridReader (the reader ParaView uses): the same points and arrays, Float64
arrays equal bit for bit, Float32 arrays the f32 rounding of the ASCII values, and the
stress tensor's components named xx, yy, zz, xy, yz, xz. Prints one line per run.

    pip install vtk numpy
    loam run SCENE --out BINARY_DIR                 # output: (vtu_format: Binary) or BinaryDouble
    loam run SCENE_WITH_ASCII --out ASCII_DIR       # the same scene, output: (vtu_format: Ascii)
    python3 scripts/check_vtu.py BINARY_DIR ASCII_DIR
"""
import pathlib
import sys

import numpy as np
import vtk
from vtk.util.numpy_support import vtk_to_numpy


def read(path):
    reader = vtk.vtkXMLUnstructuredGridReader()
    reader.SetFileName(str(path))
    reader.Update()
    grid = reader.GetOutput()
    data = grid.GetPointData()
    arrays = {"Points": grid.GetPoints().GetData()}
    arrays.update({data.GetArrayName(i): data.GetArray(i) for i in range(data.GetNumberOfArrays())})
    return grid.GetNumberOfPoints(), grid.GetNumberOfCells(), arrays


def compare(binary, ascii_):
    n, cells, b = read(binary)
    m, cells_a, a = read(ascii_)
    assert (n, cells) == (m, cells_a) and n > 0, f"{binary}: {n} points, {cells} cells against {m}, {cells_a}"
    assert sorted(b) == sorted(a), f"{binary}: arrays {sorted(b)} against {sorted(a)}"
    for name, array in b.items():
        got, want = vtk_to_numpy(array), vtk_to_numpy(a[name])
        if got.dtype == np.float32:
            ok = np.array_equal(got, want.astype(np.float32))
        else:
            ok = np.array_equal(got, want)
        assert ok, f"{binary}: {name} differs"
    stress = b.get("stress")
    if stress is not None:
        names = [stress.GetComponentName(k) for k in range(6)]
        assert names == ["xx", "yy", "zz", "xy", "yz", "xz"], f"{binary}: stress components {names}"
    return n, b["Points"].GetDataTypeAsString()


def main(binary_dir, ascii_dir):
    frames = sorted(pathlib.Path(ascii_dir).glob("points_*.vtu"))
    assert frames, f"no frames in {ascii_dir}"
    for frame in frames:
        points, kind = compare(pathlib.Path(binary_dir) / frame.name, frame)
    print(f"{len(frames)} frames of {points} points read by VTK {vtk.vtkVersion.GetVTKVersion()}: "
          f"the binary ({kind}) frames hold the ASCII frames' values")


if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2])
