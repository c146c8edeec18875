"""examples/register.py runs as documented: on its own part, and on files."""

import subprocess
import sys

import numpy as np

from conftest import REPO

EXAMPLE = REPO / "examples" / "register.py"


def run(*args):
    out = subprocess.run([sys.executable, str(EXAMPLE), *map(str, args)], capture_output=True, text=True)
    assert out.returncode == 0, out.stderr
    return out.stdout


def test_the_example_registers_its_own_part():
    out = run()
    assert out.startswith("verdict confident"), out
    lines = out.splitlines()
    start = lines.index("transformation (scan to model):") + 1
    t = np.array([[float(v) for v in line.strip(" []").split()] for line in lines[start:start + 4]])
    # The scan is one side of the part turned by 40 degrees about z and moved by (5, -3, 2) mm.
    a = np.radians(40)
    assert np.allclose(t[:2, :2], [[np.cos(a), -np.sin(a)], [np.sin(a), np.cos(a)]], atol=0.005), t
    assert np.allclose(t[:3, 3], [5, -3, 2], atol=0.05), t


def test_the_example_reads_files(model1):
    model, scan, _ = model1
    out = run(model, scan)
    assert out.startswith("verdict ") and "transformation" in out, out


def test_the_package_imports_from_every_folder_of_the_checkout():
    # python -c "import pficp" puts the working folder first on sys.path: a source folder
    # named pficp there (one without the built extension) would shadow the installed package.
    for folder in (REPO, REPO / "python", REPO / "examples"):
        out = subprocess.run([sys.executable, "-c", "import pficp; print(pficp.register.__doc__ is not None)"],
                             cwd=folder, capture_output=True, text=True)
        assert out.returncode == 0 and out.stdout.strip() == "True", (folder, out.stderr)
