#!/usr/bin/env python3
"""The error a sensor's scale leaves a self-calibration: its gauge floor.

With every link length free (the paper's mask frees the segments' and the tool's translations,
never the base's), a sensor that reads every length (1 + scale) long is explained exactly by
an arm whose free translations are (1 + scale) long: the scans fuse as well, the cost is the
same, and no calibration from the scans alone can tell the two apart (docs/engine.md,
deviation 17: the depth scale is a gauge). The calibrated model then sits at that scaled
truth, and its sensor pose error is this floor (RMS over 500 configurations, `selfcal
evaluate`), whatever the engine does. Only a length known from elsewhere breaks it.

Usage: tests/bench/field/gauge_floor.py [-b BUILD] [--scale 0.002] TRUTH.yaml...
  TRUTH.yaml  a simulated truth (`selfcal simulate`'s truth.yaml, or the field bench's
              DATA/<twin>/<variant>/seed<N>/sim/truth.yaml with --keep)
Prints per file the sensor position and orientation error of the scaled truth against it.
"""
import argparse
import os
import subprocess
import sys
import tempfile

import yaml

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", "..", ".."))


def scaled_model(model, scale):
    """The model with every segment and tool translation (1 + scale) long; the base kept."""
    scaled = dict(model)
    scaled.pop("calibration", None)  # provenance of the truth, not of this model
    scaled["segments"] = [dict(s) for s in model["segments"]]
    for segment in scaled["segments"]:
        for key in ("x", "y"):
            segment[key] = segment.get(key, 0.0) * (1 + scale)
    scaled["tool"] = dict(model["tool"])
    for key in ("x", "y", "z"):
        scaled["tool"][key] = scaled["tool"].get(key, 0.0) * (1 + scale)
    return scaled


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("-b", "--build", default=os.path.join(ROOT, "build"))
    parser.add_argument("--scale", type=float, default=0.002,
                        help="the sensor's relative scale error (default 0.002, the twins')")
    parser.add_argument("truths", nargs="+")
    args = parser.parse_args()
    selfcal = os.path.join(args.build, "tools", "selfcal")
    if not os.access(selfcal, os.X_OK):
        sys.exit("error: %s is not built (tools/test or cmake --build %s)" % (selfcal, args.build))
    with tempfile.TemporaryDirectory() as work:
        for truth in args.truths:
            with open(truth) as f:
                model = yaml.safe_load(f)
            path = os.path.join(work, "scaled.yaml")
            with open(path, "w") as f:
                yaml.safe_dump(scaled_model(model, args.scale), f, sort_keys=False)
            result = subprocess.run([selfcal, "-q", "evaluate", "--truth", truth, "--model", path],
                                    capture_output=True, text=True)
            if result.returncode != 0:
                sys.exit("error: selfcal evaluate on %s: %s" % (truth, result.stderr.strip()))
            line = next((l for l in result.stdout.splitlines() if l.startswith("sensor")), "")
            print("%s: %s" % (truth, " ".join(line.split())))


if __name__ == "__main__":
    main()
