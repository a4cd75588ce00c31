"""examples/python_convert.py runs and prints a row per percentage, D falling as the file grows."""
import os
import subprocess
import sys

EXAMPLE = os.path.join(os.path.dirname(__file__), "..", "..", "examples", "python_convert.py")


def test_the_example_runs(tmp_path):
    result = subprocess.run([sys.executable, EXAMPLE, "--size", "40", "--out", str(tmp_path)], capture_output=True,
                            text=True, check=True)
    rows = [line.split() for line in result.stdout.splitlines() if line[:8].strip().replace(".", "").isdigit()]
    assert len(rows) == 5 and (tmp_path / "two_tori.isw").exists()
    sizes = [int(r[1]) for r in rows]
    distances = [float(r[3]) for r in rows]
    assert sizes == sorted(sizes, reverse=True)
    assert distances[0] < distances[-1]
