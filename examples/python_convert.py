#!/usr/bin/env python3
"""Converts a NumPy field with isowave, decodes it at several percentages and plots D against the file size.

The field is analytic: two overlapping tori (their union is a genus-2 surface at value 0), sampled on an N^3 grid with a
cell of 0.5 world units. The script converts it to an .isw file, prints per percentage of full
resolution the bytes a progressive reader needs, the RMSE against the full decode and D (the decoded
surface's distance from the extracted isosurface, as `isowave convert` reports it), decodes the file at
each percentage, and draws D against bytes with matplotlib when it is installed.

usage: PYTHONPATH=build/python /usr/bin/python3 examples/python_convert.py [--size N] [--out DIR]
"""
import argparse
import os
import tempfile

import numpy as np

import isowave


def two_tori(n, cell):
    """field[z, y, x] (the last axis is x): positive inside two tori side by side in the z = 0 plane."""
    z, y, x = np.meshgrid(*(np.arange(n) * cell for _ in range(3)), indexing="ij")
    c = (n - 1) * cell / 2
    x, y, z = x - c, y - c, z - c
    big, small = 0.19 * n * cell, 0.08 * n * cell
    tori = [small - np.hypot(np.hypot(x - dx, y) - big / 1.6, z) for dx in (-big / 1.4, big / 1.4)]
    return np.maximum(*tori).astype(np.float32)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--size", type=int, default=96, help="samples along each axis (default 96)")
    parser.add_argument("--out", default=None, help="directory for the .isw file and the plot (default: a temporary one)")
    args = parser.parse_args()
    out = args.out or tempfile.mkdtemp(prefix="isowave_example_")
    os.makedirs(out, exist_ok=True)

    cell = 0.5
    field = two_tori(args.size, cell)
    path = os.path.join(out, "two_tori.isw")
    summary = isowave.convert(field, 0.0, path, spacing=(cell, cell, cell), source="two tori", force=True)
    print(f"{path}: {summary['bytes']} bytes for {summary['extracted_vertices']} isosurface vertices "
          f"({field.nbytes} bytes of float32 samples), {summary['levels']} levels, "
          f"{summary['base_vertices']} base vertices")

    print(f"{'percent':>8} {'bytes':>8} {'RMSE [% cell]':>14} {'D [% cell]':>11}  decoded mesh")
    sizes, distances = [], []
    for row in summary["rows"]:
        vertices, faces = isowave.decode(path, percent=row["percent"])  # the finest level, fewer coefficients
        print(f"{row['percent']:8.2f} {row['bytes']:8d} {row['rmse_percent_cell']:14.3f} {row['d_percent_cell']:11.3f}"
              f"  {len(vertices)} vertices, {len(faces)} quads" + (" (base mesh)" if row["base"] else ""))
        sizes.append(row["bytes"])
        distances.append(row["d_percent_cell"])

    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        print("matplotlib is not installed: no plot")
        return
    figure, axes = plt.subplots()
    axes.plot(sizes, distances, "o-")
    axes.set_xlabel("bytes a progressive reader needs")
    axes.set_ylabel("D [% of a cell]")
    axes.set_title("two tori: D against file size")
    figure.savefig(os.path.join(out, "d_against_size.png"))
    print(f"plot: {os.path.join(out, 'd_against_size.png')}")


if __name__ == "__main__":
    main()
