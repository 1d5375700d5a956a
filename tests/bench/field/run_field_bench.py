#!/usr/bin/env python3
"""Field benchmark: today's engine in the field twins (config/scenarios/field/).

For each scenario and seed it simulates variants of the field twin, calibrates each with
`selfcal calibrate` (latency 0: the engine is not told the sensor's latency) and measures the
sensor pose error with `selfcal evaluate` (RMS over 500 configurations). Variants:
  none     the twin without effects and without latency (the ideal world, 60 mm start)
  latency  only the twin's sensor_latency
  <key>    only that key of the twin's `effects:` section
  all      the twin as committed
  all-<key> the twin as committed but for that key (or latency): what the key adds to the rest
  <key>+<key>... only those keys (latency among them): how effects combine
Prints one row per run, then per scenario and variant the median, worst (max), mean and best
(min) calibrated sensor position error over seeds, and the median and 95th percentile of the
ratio actual / predicted sensor position error (the engine's covariance, docs/engine.md
"Covariance and observability"; runs the gate refuses count too), and of actual / the held-out
scans' registration offset (docs/engine.md "The held-out scans registered onto the fit
scans"), and of actual / the larger of the two, also pooled over every `all` run whose
prediction counts what the calibration holds. With --results FILE every run is also appended to
FILE as one JSON object per line (date, commit, scenario, variant, seed, the effects simulated,
errors, times), so that a table can be checked and rebuilt; --table FILE... prints the table of
such files without running anything (the last row of a scenario, variant and seed wins).
--planner runs `selfcal plan` per seed and simulates its scans (at most --scans) instead of the
paper-style plan's (docs/planning.md); --planner-map plans on the map of a previous session's
scans instead of the scenario's scene: the paper-style plan's --scans simulated with the same seed
and fused with the true model (`selfcal plan --map-log`, docs/planning.md "On a site").
--calibrate-args "..." passes more options to every calibration (e.g. "--elasticity
--sensor-mass 0.44", docs/engine.md deviation 15, or "--estimate-latency", deviation 16: the
estimated latency is then printed and kept as latency_ms, latency_std_ms); the table keeps such
runs apart.

Usage: tests/bench/field/run_field_bench.py [-b BUILD] [-d DATA] [--seeds N] [--first-seed N] [--scans N]
         [--variants none,all,...] [--skip-variants latency,...] [--threads N] [-k SECONDS]
         [--results FILE] [--keep] [--planner | --planner-map] SCENARIO...
       tests/bench/field/run_field_bench.py --table FILE...
  SCENARIO  kinect-bunny, kinect-office, photoneo-bunny, wenglor-bunny or hokuyo-office
Recordings are deleted after each run unless --keep (a PhotoNeo recording is about 390 MB).
Never run by ctest; docs/accuracy.md holds the table and the command that produced it.
"""
import argparse
import datetime
import json
import os
import shlex
import statistics
import subprocess
import sys
import time

import yaml

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", "..", ".."))


def variants_of(twin):
    names = ["none", "latency"] + list(twin.get("effects", {}).keys()) + ["all"]
    return names


def left_out_of(variant):
    """The effect an `all-KEY` variant leaves out of the twin (None for the other variants)."""
    return variant[len("all-"):] if variant.startswith("all-") else None


def combined_of(variant):
    """The effects a `KEY+KEY...` variant simulates (None for the other variants)."""
    return variant.split("+") if "+" in variant else None


def is_variant_of(twin, variant):
    single = [v for v in variants_of(twin) if v not in ("none", "all")]
    if left_out_of(variant) is not None:
        return left_out_of(variant) in single
    if combined_of(variant) is not None:
        return all(key in single for key in combined_of(variant))
    return variant in variants_of(twin)


def variant_scenario(twin, variant, field_dir):
    scenario = dict(twin)
    for key in ("robot", "sensor"):
        scenario[key] = os.path.normpath(os.path.join(field_dir, twin[key]))
    effects = twin.get("effects", {})
    if variant == "all":
        return scenario
    left_out = left_out_of(variant)
    if left_out is not None:  # every effect of the twin but one
        if left_out == "latency":
            scenario["sensor_latency"] = 0.0
        else:
            scenario["effects"] = {k: v for k, v in effects.items() if k != left_out}
        scenario["name"] = twin["name"] + "-" + variant
        return scenario
    scenario.pop("effects", None)
    keys = combined_of(variant) or [variant]
    scenario["sensor_latency"] = twin.get("sensor_latency", 0.0) if "latency" in keys else 0.0
    chosen = {key: effects[key] for key in keys if key in effects}
    if chosen:
        scenario["effects"] = chosen
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


def failure(status, code, log, **times):
    """A failed run's row: the status, the exit code and the end of the program's output, so
    that the reason survives the data directory."""
    tail = ""
    if os.path.exists(log):
        with open(log, errors="replace") as f:
            tail = "".join(f.readlines()[-12:])
    return dict(status=status, exit_code=code, output_tail=tail, **times)


def bench_one(selfcal, twin, variant, seed, scans, threads, limit, data, field_dir, keep, extra,
              planner=""):
    suffix = {"": "", "scene": "-planned", "map": "-planned-on-map"}[planner]
    directory = os.path.join(data, twin["name"] + suffix, variant,
                             "seed%d" % seed)
    os.makedirs(directory, exist_ok=True)
    scenario_path = os.path.join(directory, "scenario-in.yaml")
    with open(scenario_path, "w") as f:
        yaml.safe_dump(variant_scenario(twin, variant, field_dir), f, sort_keys=False)
    sim = os.path.join(directory, "sim")
    try:
        return measure(selfcal, directory, scenario_path, sim, twin, seed, scans, threads, limit,
                       field_dir, extra, planner)
    finally:
        if not keep and os.path.exists(os.path.join(sim, "recording.lcmlog")):
            os.remove(os.path.join(sim, "recording.lcmlog"))


def plan_scans(selfcal, directory, scenario_path, seed, scans, threads, limit, planner):
    """The simulate options of the run's scans: the scenario's paper-style plan of `scans`, or
    with --planner the plan `selfcal plan` chooses (at most `scans`; its time in plan_wall), with
    --planner-map on the map of a previous session's scans (its simulation not timed)."""
    if not planner:
        return ["--scans", str(scans)], None, None
    map_options = []
    if planner == "map":
        previous = os.path.join(directory, "previous")
        code, _ = run([selfcal, "-q", "simulate", scenario_path, "--out", previous, "--seed", str(seed),
                       "--threads", str(threads), "--scans", str(scans)],
                      os.path.join(directory, "previous.txt"), limit)
        if code != 0:
            return None, failure("simulate_failed", code, os.path.join(directory, "previous.txt")), None
        map_options = ["--map-log", os.path.join(previous, "recording.lcmlog"),
                       "--map-robot", os.path.join(previous, "truth.yaml")]
    planned = os.path.join(directory, "planned")
    code, wall = run([selfcal, "-q", "plan", scenario_path, "--out", planned, "--seed", str(seed),
                      "--max-scans", str(scans), "--threads", str(threads)] + map_options,
                     os.path.join(directory, "plan.txt"), limit)
    if code != 0:
        return None, failure("plan_failed", code, os.path.join(directory, "plan.txt"), plan_wall=wall), wall
    return ["--plan", os.path.join(planned, "plan.yaml")], None, wall


def measure(selfcal, directory, scenario_path, sim, twin, seed, scans, threads, limit, field_dir,
            extra, planner=""):
    scan_options, failed, plan_wall = plan_scans(selfcal, directory, scenario_path, seed, scans,
                                                 threads, limit, planner)
    if failed:
        return failed
    code, simulate_wall = run([selfcal, "-q", "simulate", scenario_path, "--out", sim, "--seed", str(seed),
                   "--threads", str(threads)] + scan_options,
                  os.path.join(directory, "simulate.txt"), limit)
    if code != 0:
        return failure("simulate_failed", code, os.path.join(directory, "simulate.txt"),
                       simulate_wall=simulate_wall)
    sensor = os.path.normpath(os.path.join(field_dir, twin["sensor"]))
    result = os.path.join(directory, "result.yaml")
    code, wall = run([selfcal, "-q", "calibrate", "--robot", os.path.join(sim, "nominal.yaml"),
                      "--sensor", sensor, "--log", os.path.join(sim, "recording.lcmlog"), "--out",
                      result, "--scans", str(scans), "--threads", str(threads)] + extra,
                     os.path.join(directory, "calibrate.txt"), limit)
    # 3: a result written that the acceptance gate refuses (its accuracy is measured all the same)
    if code not in (0, 3) or not os.path.exists(result):
        return failure("killed" if code == 124 else "calibrate_failed", code,
                       os.path.join(directory, "calibrate.txt"), wall=wall,
                       simulate_wall=simulate_wall)
    with open(result) as f:
        calibration = yaml.safe_load(f).get("calibration", {})
    predicted = calibration.get("predicted_error", {}).get("sensor", {}).get("rms_position_m")
    # the part of it from what the calibration holds at assumed values (docs/engine.md 21)
    held = calibration.get("predicted_error", {}).get("sensor_from_held", {}).get("rms_position_m")
    held_out = calibration.get("validation", {}).get("held_out_registration", {})
    held_out = held_out.get("rms_position_m") if held_out.get("scans") else None
    # --estimate-latency (docs/engine.md deviation 16): the estimated latency and its std dev
    latency = [p for p in calibration.get("parameters", []) if p.get("name") == "sensor.latency"]
    errors = {}
    for name, model in (("nominal", os.path.join(sim, "nominal.yaml")), ("calibrated", result)):
        out = subprocess.run([selfcal, "-q", "evaluate", "--truth", os.path.join(sim, "truth.yaml"),
                              "--model", model, "--samples", "500", "--json"],
                             capture_output=True, text=True, check=True).stdout
        errors[name] = json.loads(out[out.index("{"):])["sensor"]
    return dict(status="ok", wall=wall, simulate_wall=simulate_wall,
                nominal_mm=errors["nominal"]["rms_position_mm"],
                calibrated_mm=errors["calibrated"]["rms_position_mm"],
                calibrated_deg=errors["calibrated"]["rms_orientation_deg"], usable=code == 0,
                predicted_mm=predicted * 1e3 if predicted else None, plan_wall=plan_wall,
                held_out_mm=held_out * 1e3 if held_out else None,
                predicted_held_mm=held * 1e3 if held else None,
                **(dict(latency_ms=latency[0]["calibrated_s"] * 1e3,
                        latency_std_ms=latency[0]["std_dev_s"] * 1e3) if latency else {}))


def git_commit():
    try:
        return subprocess.run(["git", "-C", ROOT, "rev-parse", "HEAD"], capture_output=True,
                              text=True, check=True).stdout.strip()
    except (OSError, subprocess.CalledProcessError):
        return "unknown"


def effects_of(twin, variant):
    """The effect keys a variant simulates (latency counts as one)."""
    if variant == "none":
        return []
    if variant == "latency":
        return ["latency"]
    if variant == "all" or left_out_of(variant) is not None:
        every = (["latency"] if twin.get("sensor_latency", 0.0) else []) + list(twin.get("effects", {}))
        return [key for key in every if key != left_out_of(variant)]
    return combined_of(variant) or [variant]


def expected_mm(r):
    """The larger of the prediction and the held-out scans' offset (docs/accuracy.md, "The error
    to expect"); None without a prediction."""
    if not r.get("predicted_mm"):
        return None
    return max(r["predicted_mm"], r.get("held_out_mm") or 0.0)


def ratio_columns(ok, key):
    """Median and nearest-rank 95th percentile of actual / r[key] (or key(r)) over the runs that
    have it."""
    value = key if callable(key) else (lambda r: r.get(key))
    ratios = sorted(r["calibrated_mm"] / value(r) for r in ok if value(r))
    if not ratios:
        return "- | -"
    p95 = ratios[min(len(ratios) - 1, max(0, -(-95 * len(ratios) // 100) - 1))]
    return "%.2f | %.2f" % (statistics.median(ratios), p95)


def print_table(rows):
    """rows: dicts with scenario, variant, seed, status, calibrated_mm; the last per seed wins."""
    runs = {}
    for row in rows:  # runs with --calibrate-args are their own variant
        variant = row["variant"] + (" " + row["calibrate_args"] if row.get("calibrate_args") else "")
        if row.get("planner"):  # planned runs too, with their scan count
            on_map = " on a map" if row["planner"] == "map" else ""
            variant += " planned%s %d" % (on_map, row.get("scans", 0))
        runs[(row["scenario"], variant, row["seed"])] = row
    groups = {}
    for (name, variant, seed), row in runs.items():
        groups.setdefault((name, variant), []).append(row)
    print("\n| scenario | variant | seeds ok/run | calibrated mm RMS: median | worst | mean | best "
          "| worst orientation deg | nominal mm | actual / predicted: median | 95th percentile "
          "| actual / held-out: median | 95th percentile "
          "| actual / expected (the larger): median | 95th percentile |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|")
    for (name, variant), group in groups.items():
        ok = [r for r in group if r["status"] == "ok"]
        if not ok:
            print("| %s | %s | 0/%d | - | - | - | - | - | - | - | - | - | - | - | - |" %
                  (name, variant, len(group)))
            continue
        values = [r["calibrated_mm"] for r in ok]
        nominal = [r["nominal_mm"] for r in ok]
        print("| %s | %s | %d/%d | %.2f | %.2f | %.2f | %.2f | %.3f | %.1f-%.1f | %s | %s | %s |" % (
            name, variant, len(ok), len(group), statistics.median(values), max(values),
            statistics.mean(values), min(values), max(r["calibrated_deg"] for r in ok),
            min(nominal), max(nominal), ratio_columns(ok, "predicted_mm"),
            ratio_columns(ok, "held_out_mm"), ratio_columns(ok, expected_mm)))
    # The uncertainty's calibration over every run with every field effect whose prediction
    # counts what the calibration holds (rows that keep predicted_held_mm; docs/accuracy.md).
    field = [r for r in runs.values()
             if r["status"] == "ok" and r["variant"] == "all" and "predicted_held_mm" in r]
    if field:
        print("\nEvery `all` run above whose prediction counts what is held (%d): actual / "
              "predicted %s, / held-out %s, / expected %s (median | 95th percentile)" % (
                  len(field), ratio_columns(field, "predicted_mm"),
                  ratio_columns(field, "held_out_mm"), ratio_columns(field, expected_mm)))


def joined_calibrate_args(argv):
    """`--calibrate-args X` as `--calibrate-args=X`: argparse takes an X that starts with '-'
    (e.g. "--noise-correction") for an option of its own."""
    out = []
    for i, arg in enumerate(argv):
        if i > 0 and argv[i - 1] == "--calibrate-args":
            out[-1] = "--calibrate-args=" + arg
        else:
            out.append(arg)
    return out


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawTextHelpFormatter)
    parser.add_argument("-b", "--build", default=os.path.join(ROOT, "build"))
    parser.add_argument("-d", "--data", default=os.path.join(os.environ.get("TMPDIR", "/tmp"), "selfcal-field-bench"))
    parser.add_argument("--seeds", type=int, default=5, help="how many seeds")
    parser.add_argument("--first-seed", type=int, default=1, help="seeds first .. first + seeds - 1")
    parser.add_argument("--scans", type=int, default=28)
    parser.add_argument("--variants", default="", help="comma-separated; default: every variant")
    parser.add_argument("--skip-variants", default="", help="comma-separated variants to leave out")
    parser.add_argument("--threads", type=int, default=0)
    parser.add_argument("-k", "--limit", type=float, default=1800, help="seconds per command")
    parser.add_argument("--results", help="append one JSON object per run to this file")
    parser.add_argument("--keep", action="store_true", help="keep the recordings")
    parser.add_argument("--calibrate-args", default="",
                        help="more options for every `selfcal calibrate`, one string (e.g. "
                             "\"--elasticity --sensor-mass 0.44\"); recorded in each --results row")
    parser.add_argument("--planner", action="store_true",
                        help="the scans `selfcal plan` chooses (at most --scans) instead of the "
                             "paper-style plan's --scans (docs/planning.md); recorded as planner")
    parser.add_argument("--planner-map", action="store_true",
                        help="as --planner, on the map of a previous session's scans (selfcal plan "
                             "--map-log); recorded as planner: map")
    parser.add_argument("--table", action="store_true",
                        help="print the table of the --results files given as arguments")
    parser.add_argument("scenarios", nargs="+")
    args = parser.parse_args(joined_calibrate_args(sys.argv[1:]))
    if args.planner and args.planner_map:
        sys.exit("error: --planner and --planner-map exclude each other")
    planner_kind = "map" if args.planner_map else "scene" if args.planner else ""
    if args.table:
        rows = []
        for path in args.scenarios:
            with open(path) as f:
                rows += [json.loads(line) for line in f if line.strip()]
        print_table(rows)
        return
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
    commit = git_commit()
    print("# field bench: commit=%s build=%s data=%s seeds=%d scans=%d threads=%d host_cores=%d load=%s" %
          (commit, args.build, args.data, args.seeds, args.scans, args.threads, os.cpu_count(),
           open("/proc/loadavg").read().split()[:3]))
    print("scenario variant seed status nominal_mm calibrated_mm calibrated_deg calibrate_wall_s "
          "predicted_mm held_out_mm")
    rows = []
    skip = set(v for v in args.skip_variants.split(",") if v)
    for name, twin in twins.items():
        variants = args.variants.split(",") if args.variants else variants_of(twin)
        for variant in variants:
            if not is_variant_of(twin, variant):
                sys.exit("error: %s has no variant %s (it has %s, all-KEY and KEY+KEY... "
                         "for the keys but none and all)" % (name, variant, variants_of(twin)))
        for variant in [v for v in variants if v not in skip]:
            for seed in range(args.first_seed, args.first_seed + args.seeds):
                r = bench_one(selfcal, twin, variant, seed, args.scans, args.threads, args.limit,
                              args.data, field_dir, args.keep, shlex.split(args.calibrate_args),
                              planner_kind)
                print("%s %s %d %s %s %s %s %s %s %s" % (name, variant, seed, r["status"],
                      "%.2f" % r["nominal_mm"] if "nominal_mm" in r else "-",
                      "%.3f" % r["calibrated_mm"] if "calibrated_mm" in r else "-",
                      "%.4f" % r["calibrated_deg"] if "calibrated_deg" in r else "-",
                      "%.1f" % r["wall"] if "wall" in r else "-",
                      "%.3f" % r["predicted_mm"] if r.get("predicted_mm") else "-",
                      "%.3f" % r["held_out_mm"] if r.get("held_out_mm") else "-"), flush=True)
                if "latency_ms" in r:
                    simulated = variant_scenario(twin, variant, field_dir).get("sensor_latency", 0.0)
                    print("  estimated latency %.3f ms +- %.3f ms (simulated sensor_latency %.1f ms)" %
                          (r["latency_ms"], r["latency_std_ms"], 1e3 * simulated), flush=True)
                if "output_tail" in r:
                    print("  exit code %s; the output ended with:\n%s" % (r["exit_code"], r["output_tail"]),
                          flush=True)
                row = dict(date=datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds"),
                           commit=commit, scenario=name, variant=variant, seed=seed, scans=args.scans,
                           threads=args.threads, effects=effects_of(twin, variant),
                           load=float(open("/proc/loadavg").read().split()[0]), **r)
                if args.calibrate_args:
                    row["calibrate_args"] = args.calibrate_args
                if planner_kind == "scene":
                    row["planner"] = True
                elif planner_kind:
                    row["planner"] = "map"
                rows.append(row)
                if args.results:
                    with open(args.results, "a") as f:
                        f.write(json.dumps(row, sort_keys=True) + "\n")
    print_table(rows)


if __name__ == "__main__":
    main()
