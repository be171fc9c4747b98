"""python/examples/bench_python.py as a user runs it, briefly: both comparisons measured,
printed, and plotted (its figures are in docs/python.md; here they are only checked to
be measurements, not bounded: this machine is shared)."""

import os
import pathlib
import re
import subprocess
import sys

from conftest import AFHUB, EXAMPLES

SCRIPT = pathlib.Path(__file__).resolve().parents[2] / 'python/examples/bench_python.py'


def figures(label, text):
    """The numbers on the line that starts with `label`."""
    line = next(line for line in text.splitlines() if line.startswith(label))
    return [float(number) for number in re.findall(r'(\d+\.?\d*) us', line)]


def test_bench_python_measures_prints_and_plots(physics, tmp_path):
    run = physics(EXAMPLES / 'arm7.yaml')
    run.wait_for_body('arm/base')
    png = tmp_path / 'python_bench.png'
    result = subprocess.run(
        [sys.executable, str(SCRIPT), 'arm/base', '--count', '300', '--seconds', '2',
         '--plot', str(png)],
        capture_output=True, text=True, timeout=120, env=dict(os.environ, AFHUB=AFHUB))
    assert result.returncode == 0, result.stdout + result.stderr
    for label, count in (('afhub read + command', 2), ('rospy round trip', 2),
                         ('rospy publish()', 2), ('C++ ctl hold', 4),
                         ('Python afhub.Loop', 4)):
        values = figures(label, result.stdout)
        assert len(values) == count and all(value > 0 for value in values), result.stdout
        assert values[0] <= values[1], f'{label}: p50 above p99\n{result.stdout}'
    assert png.read_bytes()[:8] == b'\x89PNG\r\n\x1a\n'
