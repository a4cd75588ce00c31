"""The ParaView reader (python/paraview/isowave_reader.py) against `isowave decode` (issue #50, item 1).

Run by ctest (test paraview_reader) under xvfb-run with ParaView's Python (paraview.simple), the
module on PYTHONPATH and ISOWAVE_CLI naming the binary; usage: check_paraview_reader.py PLUGIN WORKDIR.
For each property setting (the finest level, a percentage, a byte prefix, a maximum error, the base
level, the limit surface): the reader's points and polygons equal those of the PLY `isowave decode`
writes with the same options (read by ParaView's own PLY reader), and renderings of the two with one
camera agree; the "level" array counts each level's vertices as decodes at coarser levels do, and
"detail" is zero on base vertices; a truncated or corrupt file gives an error message and no output.
"""
import json
import os
import runpy
import subprocess
import sys

import numpy as np
from paraview import servermanager
from paraview.simple import (GetActiveViewOrCreate, Hide, OpenDataFile, PLYReader, ResetCamera, SaveScreenshot, Show,
                             UpdatePipeline)
from vtkmodules.numpy_interface import dataset_adapter as dsa
from vtkmodules.vtkCommonCore import vtkOutputWindow, vtkStringOutputWindow
from vtkmodules.vtkIOImage import vtkPNGReader

FAILURES = []


def check(condition, message):
    if not condition:
        FAILURES.append(message)
        sys.__stderr__.write("FAIL: %s\n" % message)


def cli(*args):
    result = subprocess.run([os.environ["ISOWAVE_CLI"], *map(str, args)], capture_output=True, text=True)
    if result.returncode != 0:
        raise SystemExit("isowave %s failed: %s" % (" ".join(map(str, args)), result.stderr))
    return result


def arrays(source):
    """Points (n, 3), polygon offsets and corners, and point arrays of a proxy's output."""
    data = servermanager.Fetch(source)
    wrapped = dsa.WrapDataObject(data)
    polys = data.GetPolys()
    offsets = dsa.vtkDataArrayToVTKArray(polys.GetOffsetsArray())
    corners = dsa.vtkDataArrayToVTKArray(polys.GetConnectivityArray())
    return np.asarray(wrapped.Points), np.asarray(offsets), np.asarray(corners), wrapped.PointData


def image(source, path, view):
    """A rendering of `source` alone, from the camera the first rendering set."""
    display = Show(source, view)
    view.ViewSize = [320, 240]
    if not getattr(image, "camera_set", False):
        ResetCamera(view)
        image.camera_set = True
    SaveScreenshot(path, view, ImageResolution=[320, 240])
    Hide(source, view)
    reader = vtkPNGReader()
    reader.SetFileName(path)
    reader.Update()
    return np.asarray(dsa.WrapDataObject(reader.GetOutput()).PointData[0], dtype=np.float64)


def main(plugin, workdir):
    os.makedirs(workdir, exist_ok=True)
    isw = os.path.join(workdir, "sphere.isw")
    cli("convert", "builtin:sphere:32", "--levels", "3", "-o", isw, "--force", "--quiet")
    runpy.run_path(plugin, run_name="__main__")  # as a user runs it: it loads itself
    reader = OpenDataFile(isw)
    check(reader.GetXMLName() == "IsowaveReader", "File > Open chose %s" % reader.GetXMLName())
    view = GetActiveViewOrCreate("RenderView")

    settings = [
        ({}, []),
        ({"Percent": 20.0}, ["--percent", "20"]),
        ({"Bytes": os.path.getsize(isw) // 2}, ["--bytes", str(os.path.getsize(isw) // 2)]),
        ({"MaxError": 0.5}, ["--max-error", "0.5"]),
        ({"Level": 0}, ["--level", "0"]),
        ({"Level": 1, "LimitSurface": 1}, ["--level", "1", "--limit"]),
    ]
    for properties, options in settings:
        name = json.dumps(properties)
        for key, value in {"Percent": 100.0, "Bytes": 0, "MaxError": 0.0, "Level": -1, "LimitSurface": 0}.items():
            setattr(reader, key, properties.get(key, value))
        UpdatePipeline(proxy=reader)
        points, offsets, corners, point_data = arrays(reader)
        ply = os.path.join(workdir, "decoded.ply")
        cli("decode", isw, *options, "-o", ply, "--force", "--quiet")
        reference = PLYReader(FileNames=[ply])
        UpdatePipeline(proxy=reference)
        ref_points, ref_offsets, ref_corners, _ = arrays(reference)
        check(points.shape == ref_points.shape, "%s: %s points, decode %s" % (name, points.shape, ref_points.shape))
        if points.shape == ref_points.shape:
            scale = np.abs(ref_points).max()
            check(np.abs(points - ref_points).max() <= 1e-6 * scale, "%s: points differ from decode's" % name)
        check(np.array_equal(offsets, ref_offsets) and np.array_equal(corners, ref_corners),
              "%s: polygons differ from decode's" % name)
        mine = image(reader, os.path.join(workdir, "reader.png"), view)
        theirs = image(reference, os.path.join(workdir, "decode.png"), view)
        difference = np.abs(mine - theirs).mean() / 255
        check(difference < 0.002 and mine.std() > 1, "%s: renderings differ by %.4f" % (name, difference))
        detail, born = np.asarray(point_data["detail"]), np.asarray(point_data["level"])
        check(np.all(detail[born == 0] == 0), "%s: detail on base vertices" % name)
        print("%s: %d points, %d polygons, rendering difference %.5f" % (name, len(points), len(offsets) - 1,
                                                                          difference))

    # The level array: as many vertices of each level as decodes at coarser levels add.
    counts = []
    for level in range(0, 4):
        reader.Level, reader.Percent, reader.LimitSurface = level, 100.0, 0
        UpdatePipeline(proxy=reader)
        counts.append(len(arrays(reader)[0]))
    born = np.asarray(arrays(reader)[3]["level"])
    expected = np.diff([0] + counts)
    check(np.array_equal(np.bincount(born, minlength=4), expected),
          "level counts %s, decodes at levels 0..3 add %s" % (np.bincount(born).tolist(), expected.tolist()))
    check(np.asarray(arrays(reader)[3]["detail"]).max() > 0, "no detail anywhere")

    # Damaged files: an error message, no output.
    errors, previous = vtkStringOutputWindow(), vtkOutputWindow.GetInstance()
    vtkOutputWindow.SetInstance(errors)  # (ParaView sends Python's prints there too, until restored)
    with open(isw, "rb") as f:
        data = f.read()
    for label, damaged in [("truncated", data[:40]), ("corrupt", data[:60] + bytes([data[60] ^ 0x5A]) + data[61:])]:
        path = os.path.join(workdir, label + ".isw")
        with open(path, "wb") as f:
            f.write(damaged)
        reader.FileName = path
        reader.Level = -1
        try:
            UpdatePipeline(proxy=reader)
        except RuntimeError:
            pass
        text = errors.GetOutput()
        check("IsowaveReader: " + path in text, "%s file: no error message naming it (%r)" % (label, text[-300:]))
        check(servermanager.Fetch(reader).GetNumberOfPoints() == 0, "%s file: output not empty" % label)
    vtkOutputWindow.SetInstance(previous)
    if FAILURES:
        raise SystemExit("%d failures: %s" % (len(FAILURES), "; ".join(FAILURES)))
    print("paraview reader: all checks passed")


if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2])
