#!/usr/bin/env python3
"""Field benchmark: today's engine in the field twins (config/scenarios/field/).

For each scenario and seed it simulates variants of the field twin, calibrates each with
`selfcal calibrate` (latency 0: the engine is not told the sensor's latency) and measures the
sensor pose error with `selfcal evaluate` (RMS over 500 configurations). Variants:
  none     the twin without effects and without latency (the ideal world, 60 mm start)
  latency  only the twin's sensor_latency
  <key>    only that key of the twin's `effects:` section
  all      the twin as committed
Prints one machine-readable row per run, then per scenario the mean, min and max over seeds.

Usage: tests/bench/field/run_field_bench.py [-b BUILD] [-d DATA] [--seeds N] [--first-seed N] [--scans N]
         [--variants none,all,...] [--threads N] [-k SECONDS] SCENARIO...
  SCENARIO  kinect-bunny, kinect-office, photoneo-bunny, wenglor-bunny or hokuyo-office
Never run by ctest; docs/accuracy.md holds the table and the command that produced it.
"""
import argparse
import json
import os
import subprocess
import sys
import time

import yaml

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", "..", ".."))


def variants_of(twin):
    names = ["none", "latency"] + list(twin.get("effects", {}).keys()) + ["all"]
    return names


def variant_scenario(twin, variant, field_dir):
    scenario = dict(twin)
    for key in ("robot", "sensor"):
        scenario[key] = os.path.normpath(os.path.join(field_dir, twin[key]))
    effects = twin.get("effects", {})
    if variant == "all":
        return scenario
    scenario.pop("effects", None)
    scenario["sensor_latency"] = twin.get("sensor_latency", 0.0) if variant == "latency" else 0.0
    if variant not in ("none", "latency"):
        scenario["effects"] = {variant: effects[variant]}
    scenario["name"] = twin["name"] + "-" + variant
    return scenario


def run(command, log, limit):
    start = time.time()
    with open(log, "w") as out:
        try:
            code = subprocess.run(command, stdout=out, stderr=subprocess.STDOUT, timeout=limit).returncode
        except subprocess.TimeoutExpired:
            code = 124
    return code, time.time() - start


def bench_one(selfcal, twin, variant, seed, scans, threads, limit, data, field_dir):
    directory = os.path.join(data, twin["name"], variant, "seed%d" % seed)
    os.makedirs(directory, exist_ok=True)
    scenario_path = os.path.join(directory, "scenario-in.yaml")
    with open(scenario_path, "w") as f:
        yaml.safe_dump(variant_scenario(twin, variant, field_dir), f, sort_keys=False)
    sim = os.path.join(directory, "sim")
    code, _ = run([selfcal, "-q", "simulate", scenario_path, "--out", sim, "--seed", str(seed),
                   "--scans", str(scans), "--threads", str(threads)],
                  os.path.join(directory, "simulate.txt"), limit)
    if code != 0:
        return dict(status="simulate_failed")
    sensor = os.path.normpath(os.path.join(field_dir, twin["sensor"]))
    result = os.path.join(directory, "result.yaml")
    code, wall = run([selfcal, "-q", "calibrate", "--robot", os.path.join(sim, "nominal.yaml"),
                      "--sensor", sensor, "--log", os.path.join(sim, "recording.lcmlog"), "--out",
                      result, "--scans", str(scans), "--threads", str(threads)],
                     os.path.join(directory, "calibrate.txt"), limit)
    if code != 0 or not os.path.exists(result):
        return dict(status="killed" if code == 124 else "calibrate_failed", wall=wall)
    errors = {}
    for name, model in (("nominal", os.path.join(sim, "nominal.yaml")), ("calibrated", result)):
        out = subprocess.run([selfcal, "-q", "evaluate", "--truth", os.path.join(sim, "truth.yaml"),
                              "--model", model, "--samples", "500", "--json"],
                             capture_output=True, text=True, check=True).stdout
        errors[name] = json.loads(out[out.index("{"):])["sensor"]
    return dict(status="ok", wall=wall, nominal_mm=errors["nominal"]["rms_position_mm"],
                calibrated_mm=errors["calibrated"]["rms_position_mm"],
                calibrated_deg=errors["calibrated"]["rms_orientation_deg"])


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawTextHelpFormatter)
    parser.add_argument("-b", "--build", default=os.path.join(ROOT, "build"))
    parser.add_argument("-d", "--data", default=os.path.join(os.environ.get("TMPDIR", "/tmp"), "selfcal-field-bench"))
    parser.add_argument("--seeds", type=int, default=5, help="how many seeds")
    parser.add_argument("--first-seed", type=int, default=1, help="seeds first .. first + seeds - 1")
    parser.add_argument("--scans", type=int, default=28)
    parser.add_argument("--variants", default="", help="comma-separated; default: every variant")
    parser.add_argument("--threads", type=int, default=0)
    parser.add_argument("-k", "--limit", type=float, default=1800, help="seconds per command")
    parser.add_argument("scenarios", nargs="+")
    args = parser.parse_args()
    selfcal = os.path.join(args.build, "tools", "selfcal")
    if not os.access(selfcal, os.X_OK):
        sys.exit("error: %s not built" % selfcal)
    field_dir = os.path.join(ROOT, "config", "scenarios", "field")
    twins = {}
    for name in args.scenarios:
        path = os.path.join(field_dir, name + ".yaml")
        if not os.path.exists(path):
            sys.exit("error: no field twin %s" % path)
        with open(path) as f:
            twins[name] = yaml.safe_load(f)
    print("# field bench: build=%s data=%s seeds=%d scans=%d threads=%d host_cores=%d load=%s" %
          (args.build, args.data, args.seeds, args.scans, args.threads, os.cpu_count(),
           open("/proc/loadavg").read().split()[:3]))
    print("scenario variant seed status nominal_mm calibrated_mm calibrated_deg calibrate_wall_s")
    summary = {}
    for name, twin in twins.items():
        variants = args.variants.split(",") if args.variants else variants_of(twin)
        for variant in variants:
            if variant not in variants_of(twin):
                sys.exit("error: %s has no variant %s (it has %s)" % (name, variant, variants_of(twin)))
            for seed in range(args.first_seed, args.first_seed + args.seeds):
                r = bench_one(selfcal, twin, variant, seed, args.scans, args.threads, args.limit,
                              args.data, field_dir)
                print("%s %s %d %s %s %s %s %s" % (name, variant, seed, r["status"],
                      "%.2f" % r["nominal_mm"] if "nominal_mm" in r else "-",
                      "%.3f" % r["calibrated_mm"] if "calibrated_mm" in r else "-",
                      "%.4f" % r["calibrated_deg"] if "calibrated_deg" in r else "-",
                      "%.1f" % r["wall"] if "wall" in r else "-"), flush=True)
                if r["status"] == "ok":
                    summary.setdefault((name, variant), []).append(r["calibrated_mm"])
    print("\n| scenario | variant | seeds | calibrated mm RMS: mean | min | max |")
    print("|---|---|---|---|---|---|")
    for (name, variant), values in summary.items():
        print("| %s | %s | %d | %.2f | %.2f | %.2f |" % (name, variant, len(values),
              sum(values) / len(values), min(values), max(values)))


if __name__ == "__main__":
    main()
