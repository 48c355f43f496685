#!/usr/bin/python3
"""The Python package's costs (docs/python.md, "Speed"), each measured against its reference in
the same run, alternating, medians of --repeats:

  run_overhead       rotorguard.run(forest, out=DIR) against `rotorguard run forest --out DIR`
                     (the same flight and files): the ratio of wall times, target <= 1.05;
  python_controller  the hover scenario stepped from Python at the control rate (200 Hz) with the
                     numpy copy of the nominal controller (examples/python/nominal_controller.py):
                     the real-time factor, target >= 50; beside it the same stepping without a
                     controller, and rotorguard.run;
  threads            two flights in two threads against the same two one after the other: the
                     speed-up (the GIL is released while a flight runs).

    PYTHONPATH=build/python /usr/bin/python3 benchmarks/python_bench.py [--repeats 3] [--json]
"""
import argparse
import concurrent.futures
import importlib.util
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time

import rotorguard

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
SCENARIOS = os.path.join(ROOT, "configs", "scenarios")


def load_example(name):
    spec = importlib.util.spec_from_file_location(name, os.path.join(ROOT, "examples", "python", name + ".py"))
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def wall(f):
    start = time.perf_counter()
    f()
    return time.perf_counter() - start


def run_overhead(cli, repeats, duration):
    forest = os.path.join(SCENARIOS, "forest.yaml")
    overrides = [] if duration is None else ["--set", f"duration_s={duration}"]
    python_set = None if duration is None else {"duration_s": duration}
    cli_s, python_s = [], []
    with tempfile.TemporaryDirectory() as tmp:
        for _ in range(repeats):  # alternating, so that a slow spell of the machine hits both
            cli_s.append(wall(lambda: subprocess.run(
                [cli, "run", forest, "--out", os.path.join(tmp, "cli"), "-q", "--no-report", *overrides],
                check=False, capture_output=True)))
            python_s.append(wall(lambda: rotorguard.run(forest, set=python_set, out=os.path.join(tmp, "py"))))
    c, p = statistics.median(cli_s), statistics.median(python_s)
    return {"cli_s_median": c, "python_s_median": p, "ratio": p / c, "repeats": repeats,
            "sim_s": duration if duration is not None else rotorguard.load_scenario(forest).duration_s}


def python_controller(repeats, duration):
    example = load_example("nominal_controller")
    hover = os.path.join(SCENARIOS, "hover.yaml")
    overrides = {"duration_s": duration}

    def stepped(with_controller):
        flight = rotorguard.Flight(hover, set=overrides, log=False)
        controller = example.NominalController(flight.stack.model, flight.scenario.options["stack"]["nominal"])
        while not flight.done:
            if with_controller:
                flight.step_control(controller(flight.time_s, flight.stack.estimate, flight.stack.reference))
            else:
                flight.step_control()
        flight.finish()

    times = {"controller": [], "stepping": [], "run": []}
    for _ in range(repeats):
        times["controller"].append(wall(lambda: stepped(True)))
        times["stepping"].append(wall(lambda: stepped(False)))
        times["run"].append(wall(lambda: rotorguard.run(hover, set=overrides, log=False)))
    rate = rotorguard.load_scenario(hover).control_rate_hz
    return {f"{k}_realtime_factor": duration / statistics.median(v) for k, v in times.items()} | {
        "control_rate_hz": rate, "sim_s": duration, "repeats": repeats}


def threads(repeats, duration):
    scenario = os.path.join(SCENARIOS, "fdd_hover_propeller_loss.yaml")

    def one(seed):
        rotorguard.run(scenario, set={"duration_s": duration}, seed=seed, log=False)

    serial, parallel = [], []
    for _ in range(repeats):
        serial.append(wall(lambda: (one(1), one(2))))
        with concurrent.futures.ThreadPoolExecutor(max_workers=2) as pool:
            parallel.append(wall(lambda: list(pool.map(one, (1, 2)))))
    s, p = statistics.median(serial), statistics.median(parallel)
    return {"serial_s_median": s, "two_threads_s_median": p, "speedup": s / p, "cores": os.cpu_count(),
            "sim_s": duration, "repeats": repeats}


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--forest-duration", type=float, help="seconds of the forest flight (default: its 120)")
    parser.add_argument("--hover-duration", type=float, default=20.0)
    parser.add_argument("--cli", default=os.path.join(ROOT, "build", "bin", "rotorguard"))
    parser.add_argument("--parts", default="run_overhead,python_controller,threads",
                        help="which measurements, comma-separated (default: all three)")
    parser.add_argument("--json", action="store_true")
    args = parser.parse_args()
    if args.repeats < 1:
        parser.error(f"--repeats {args.repeats} is invalid; expected an integer >= 1")
    parts = {
        "run_overhead": lambda: run_overhead(args.cli, args.repeats, args.forest_duration),
        "python_controller": lambda: python_controller(args.repeats, args.hover_duration),
        "threads": lambda: threads(args.repeats, args.hover_duration),
    }
    chosen = args.parts.split(",")
    for part in chosen:
        if part not in parts:
            parser.error(f"--parts: '{part}' is invalid; expected some of {', '.join(parts)}")
    results = {part: parts[part]() for part in chosen}
    if args.json:
        print(json.dumps(results, indent=2))
        return 0
    if "run_overhead" in results:
        o = results["run_overhead"]
        print(f"run overhead (forest, {o['sim_s']:g} s): rotorguard.run {o['python_s_median']:.2f} s, "
              f"CLI {o['cli_s_median']:.2f} s: ratio {o['ratio']:.3f} (target <= 1.05)")
    if "python_controller" in results:
        c = results["python_controller"]
        print(f"hover stepped from Python at {c['control_rate_hz']:g} Hz ({c['sim_s']:g} s): "
              f"{c['controller_realtime_factor']:.0f}x real time with the numpy controller (target >= 50), "
              f"{c['stepping_realtime_factor']:.0f}x stepping alone, {c['run_realtime_factor']:.0f}x run")
    if "threads" in results:
        t = results["threads"]
        print(f"two flights ({t['sim_s']:g} s each): {t['serial_s_median']:.2f} s one after the other, "
              f"{t['two_threads_s_median']:.2f} s in two threads: {t['speedup']:.2f}x on {t['cores']} cores")
    return 0


if __name__ == "__main__":
    sys.exit(main())
