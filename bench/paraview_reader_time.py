#!/usr/bin/env python3
"""Issue #50's ParaView target: opening a file at a percentage in ParaView and rendering it, against
`isowave decode` of the same percentage writing a PLY, and against ParaView opening and rendering
that PLY (what a user did before the reader; the same rendering), same run, best of 3 each.

usage: python/tests/paraview/with_xvfb.sh python3 bench/paraview_reader_time.py FILE.isw [PERCENT]
(PYTHONPATH naming the module's directory, ISOWAVE_CLI the binary; PERCENT default 20). The ParaView
time runs from OpenDataFile to the first rendered image (1920 x 1080) of a fresh reader; the decode
time is the CLI's wall time, its PLY write included; the PLY time from OpenDataFile of the PLY to its
first image.
"""
import os
import runpy
import subprocess
import sys
import tempfile
import time

from paraview.simple import Delete, GetActiveViewOrCreate, Hide, OpenDataFile, Render, ResetCamera, Show

PLUGIN = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "python", "paraview", "isowave_reader.py")


def main(path, percent):
    runpy.run_path(PLUGIN, run_name="__main__")
    view = GetActiveViewOrCreate("RenderView")
    view.ViewSize = [1920, 1080]
    paraview_times, decode_times, ply_times = [], [], []
    for _ in range(3):
        start = time.perf_counter()
        reader = OpenDataFile(path)
        reader.Percent = percent
        Show(reader, view)
        ResetCamera(view)
        Render(view)
        paraview_times.append(time.perf_counter() - start)
        points = reader.GetDataInformation().GetNumberOfPoints()
        Hide(reader, view)
        Delete(reader)
        with tempfile.TemporaryDirectory() as work:
            ply = os.path.join(work, "out.ply")
            start = time.perf_counter()
            subprocess.run([os.environ["ISOWAVE_CLI"], "decode", path, "--percent", str(percent), "-o", ply,
                            "--quiet"], check=True)
            decode_times.append(time.perf_counter() - start)
            start = time.perf_counter()
            opened = OpenDataFile(ply)
            Show(opened, view)
            ResetCamera(view)
            Render(view)
            ply_times.append(time.perf_counter() - start)
            Hide(opened, view)
            Delete(opened)
    best_paraview, best_decode, best_ply = min(paraview_times), min(decode_times), min(ply_times)
    print("%s at %g%%: %d points; ParaView open + render %.2f s; isowave decode %.2f s (%.2fx); ParaView opening "
          "and rendering decode's PLY %.2f s (decode + PLY %.2f s: %.2fx)" %
          (path, percent, points, best_paraview, best_decode, best_paraview / best_decode, best_ply,
           best_decode + best_ply, best_paraview / (best_decode + best_ply)))


if __name__ == "__main__":
    main(sys.argv[1], float(sys.argv[2]) if len(sys.argv) > 2 else 20.0)
