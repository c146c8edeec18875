"""Run a `pficp` binary's `register --json` on every exported case and score it with the
benchmark's rule (the same `score` as run_peers.py): for comparing versions of PF-ICP on
the same cases, e.g. a build from before the realistic benchmark existed.

    peers-venv/bin/python tests/peers/run_cli.py DIR PATH/TO/pficp [STEP]

DIR is an export of `pficp eval --suite realistic --export DIR`; STEP > 1 takes every
STEP-th case. Prints successes per family and the median of the tool's own `seconds`.
"""
import collections
import json
import os
import subprocess
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from run_peers import score  # noqa: E402


def main(argv):
    directory, exe = argv[1], argv[2]
    step = int(argv[3]) if len(argv) > 3 else 1
    doc = json.load(open(os.path.join(directory, "cases.json")))
    results = collections.defaultdict(lambda: [0, 0, []])
    for k, case in enumerate(doc["cases"]):
        if k % step:
            continue
        cmd = [exe, "register", "--model", os.path.join(directory, case["model"]),
               "--scan", os.path.join(directory, case["scan"]), "--seed", str(case["seed"]), "--json"]
        out = subprocess.run(cmd, capture_output=True, text=True, check=True)
        j = json.loads(out.stdout)
        est = (j["scale"], np.asarray(j["rotation"]), np.asarray(j["translation"]))
        s = score(est, case, doc["tolerance"])
        r = results[case["family"]]
        r[0] += bool(s["success"])
        r[1] += 1
        r[2].append(j["seconds"])
    for family, (ok, n, times) in results.items():
        print(f"{family:14s} {ok}/{n}  median {np.median(times):.3f} s")


if __name__ == "__main__":
    main(sys.argv)
