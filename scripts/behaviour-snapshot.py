#!/usr/bin/python3
"""What a rotorguard build does, minus its timings: a folder to diff against another build's.

Restructuring the code must not change what it computes. This script flies every scenario in
configs/scenarios/, runs every benchmark at a small size with --json, validates every config file,
and tries a list of bad command lines, with the build given; it writes what came out, with the
wall-clock figures removed, into one folder. Two folders made by two builds are then compared with
`diff -r`: an empty diff means the same flights (log.csv, scene.json, sensors.csv, vehicle.yaml and
truth_vehicle.yaml byte for byte, the NMPC's solve-time column aside), the same summaries and benchmark figures (timing
keys aside), and the same error messages and exit codes.

    scripts/behaviour-snapshot.py build/bin/rotorguard /tmp/snap-after [--qp-instance FILE] [--truth ideal]
    diff -r /tmp/snap-before /tmp/snap-after

`--truth ideal` flies every scenario that states a world, and every benchmark that has a world, in
that one: a snapshot of a build from before the realistic world became the default is compared
with `--truth ideal` of a later one.

Takes about 80 s on a 2-core machine: the scenarios one after another, the sampled benchmarks with
--jobs 2. Standard library only (Debian's python3).
"""
import argparse
import hashlib
import json
import os
import re
import shutil
import subprocess
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))

# Keys whose values are wall-clock measurements or facts of the machine and the build: left out of
# the comparison. Everything else a summary or a benchmark reports must be the same.
TIMING_KEY = re.compile(
    r"(_ms($|_)|_us($|_)|^wall|realtime|per_s|_per_sim_s|^cost|^host$|^cpu$|^git_revision$|^version$|"
    r"^started$|^finished$|^date$|scaling_efficiency|^elapsed|^time_s$|_time_s_mean$|solve_time|^time_ratio_|^meets_.*speed|^meets_targets$)")
# Output lines that carry timings (the run's table) or the program's own paths.
TIMING_LINE = re.compile(r"^(simulated |report: |trials/s )")
# Timings inside a line that otherwise counts (the odometry's time per frame).
TIMING_IN_LINE = re.compile(r"[0-9.]+ ms per frame")
# The log's only wall-clock column.
TIMING_COLUMNS = {"nmpc_ms"}


def strip_timing(value, dropped, path=""):
    if isinstance(value, dict):
        out = {}
        for k, v in value.items():
            if TIMING_KEY.search(k):
                dropped.add(re.sub(r"\.\d+", ".N", f"{path}.{k}".lstrip(".")))
                continue
            out[k] = strip_timing(v, dropped, f"{path}.{k}")
        return out
    if isinstance(value, list):
        return [strip_timing(v, dropped, f"{path}.{i}") for i, v in enumerate(value)]
    return value


def normalised_json(text, dropped, work=None):
    if work:
        text = text.replace(work, "WORK")
    return json.dumps(strip_timing(json.loads(text), dropped), indent=1, sort_keys=True) + "\n"


def normalised_csv(text):
    lines = text.splitlines()
    header = lines[0].split(",")
    keep = [i for i, name in enumerate(header) if name not in TIMING_COLUMNS]
    return "\n".join(",".join(cells[i] for i in keep) for cells in (line.split(",") for line in lines)) + "\n"


def digest(text):
    return hashlib.sha256(text.encode()).hexdigest() + "\n"


class Snapshot:
    def __init__(self, exe, out, truth=None):
        self.exe = os.path.abspath(exe)
        self.truth = truth
        self.out = out
        self.work = tempfile.mkdtemp(prefix="rotorguard-snapshot-")
        self.dropped = set()

    def write(self, rel, text):
        path = os.path.join(self.out, rel)
        os.makedirs(os.path.dirname(path), exist_ok=True)
        with open(path, "w") as f:
            f.write(text)

    def run(self, args, timeout=3600):
        r = subprocess.run([self.exe] + args, cwd=ROOT, capture_output=True, text=True, timeout=timeout)
        return r.returncode, r.stdout, r.stderr

    def stdout_lines(self, text):
        text = text.replace(self.work, "WORK")
        return "".join(TIMING_IN_LINE.sub("N ms per frame", line) + "\n" for line in text.splitlines()
                       if not TIMING_LINE.match(line))

    def scenarios(self):
        folder = os.path.join(ROOT, "configs", "scenarios")
        for name in sorted(os.listdir(folder)):
            if not name.endswith(".yaml"):
                continue
            stem = name[:-5]
            run_dir = os.path.join(self.work, "runs", stem)
            print(f"  run {name}", file=sys.stderr, flush=True)
            world = []
            if self.truth and re.search(r"^truth:", open(os.path.join(folder, name)).read(), re.M):
                world = ["--set", f"truth={self.truth}"]
            code, out, err = self.run(["run", f"configs/scenarios/{name}", "--out", run_dir, "--no-report"] + world)
            base = f"scenarios/{stem}/"
            self.write(base + "exit", f"{code}\n{err}")
            self.write(base + "stdout", self.stdout_lines(out))
            for f in ["summary.json", "log.csv", "scene.json", "sensors.csv", "vehicle.yaml",
                      "truth_vehicle.yaml"]:
                path = os.path.join(run_dir, f)
                if not os.path.exists(path):
                    self.write(base + f + ".missing", "")
                    continue
                text = open(path).read()
                if f == "summary.json":
                    self.write(base + f, normalised_json(text, self.dropped))
                elif f == "log.csv":
                    self.write(base + f + ".sha256", digest(normalised_csv(text)))
                else:
                    self.write(base + f + ".sha256", digest(text))

    def benches(self, qp_instance):
        runs = os.path.join(self.work, "runs")
        calibration_runs = [os.path.join(runs, s) for s in
                            ("hover", "fdd_hover_motor_stop", "fdd_hover_propeller_loss", "takeoff",
                             "fdd_takeoff_propeller_loss")]
        cases = {
            "sim": ["bench", "sim", "--duration", "3", "--repetitions", "1", "--json"],
            "nmpc": ["bench", "nmpc", "--json"],
            "ftc": ["bench", "ftc", "--trials", "2", "--json", "--jobs", "2"],
            "perception": ["bench", "perception", "--duration", "1", "--json"],
            "planner": ["bench", "planner", "--pairs", "10", "--worlds", "2", "--json"],
            "nav": ["bench", "nav", "--trials", "1", "--json", "--jobs", "2"],
            "flatness": ["bench", "flatness", "--seeds", "2", "--json", "--jobs", "2"],
            "mars": ["bench", "mars", "--trials", "1", "--json", "--jobs", "2"],
            "campaign": ["bench", "campaign", "--json"],
            "fdd-calibrate": ["fdd-calibrate", "--json"] + calibration_runs,
        }
        if qp_instance:
            cases["qp"] = ["bench", "qp", "--instance", os.path.abspath(qp_instance), "--repetitions", "1", "--json"]
        if self.truth:
            for name in ("ftc", "nav", "flatness", "mars"):
                cases[name] = cases[name] + ["--truth", self.truth]
        for name, args in cases.items():
            print(f"  {' '.join(args[:2])}", file=sys.stderr, flush=True)
            code, out, err = self.run(args)
            self.write(f"bench/{name}/exit", f"{code}\n{self.stdout_lines(err)}")
            try:
                self.write(f"bench/{name}/result.json", normalised_json(out, self.dropped, self.work))
            except json.JSONDecodeError:
                self.write(f"bench/{name}/stdout", self.stdout_lines(out))

    def campaigns(self):
        spec = "configs/campaigns/fdd_hover.yaml"
        out = os.path.join(self.work, "campaign")
        code, stdout, err = self.run(["campaign", "run", spec, "--out", out, "--jobs", "2", "--quiet"])
        self.write("campaign/run", f"{code}\n{self.stdout_lines(stdout)}{err}")
        code, stdout, err = self.run(["campaign", "merge", out])
        self.write("campaign/merge", f"{code}\n{self.stdout_lines(stdout)}{err}")
        if os.path.exists(os.path.join(out, "summary.json")):
            self.write("campaign/summary.json",
                       normalised_json(open(os.path.join(out, "summary.json")).read(), self.dropped))
        slurm = os.path.join(self.work, "slurm")
        code, stdout, err = self.run(["campaign", "slurm", spec, "--shards", "3", "--out", slurm])
        self.write("campaign/slurm", f"{code}\n{self.stdout_lines(stdout)}{err}")

    def validations(self):
        for kind in ("vehicles", "scenarios", "assemblies", "campaigns"):
            folder = os.path.join(ROOT, "configs", kind)
            for name in sorted(os.listdir(folder)):
                code, out, err = self.run(["validate", f"configs/{kind}/{name}"])
                self.write(f"validate/{kind}/{name}", f"{code}\n{out}{err}")

    def bad_inputs(self):
        """Command lines and files a user gets wrong: each one's exit code and message."""
        bad = os.path.join(self.work, "bad")
        os.makedirs(bad, exist_ok=True)
        vehicle_file = os.path.join(ROOT, "configs", "vehicles", "zhou2025_quad.yaml")
        hover = open(os.path.join(ROOT, "configs", "scenarios", "hover.yaml")).read().replace(
            "../vehicles/zhou2025_quad.yaml", vehicle_file)
        no_stack = hover.replace("stack:\n  controller: nominal\n", "")
        no_mission = no_stack.replace("mission:\n  type: hover\n", "")
        vehicle = open(vehicle_file).read()
        files = {
            "typo_key.yaml": hover.replace("duration_s:", "duration_sec:"),
            "duplicate_key.yaml": hover + "\nduration_s: 3\n",
            "unit_string.yaml": hover.replace("duration_s: 10.0", "duration_s: 10s"),
            "nan.yaml": hover.replace("duration_s: 10.0", "duration_s: .nan"),
            "no_mission.yaml": no_mission,
            "bad_fault_rotor.yaml": hover + "\nfaults:\n  - {rotor: 7, kind: motor_stop, onset: {at_time_s: 1.0}}\n",
            "not_yaml.yaml": "a: [1, 2\n",
            "empty.yaml": "",
            "list_top.yaml": "- 1\n- 2\n",
            "negative_mass.yaml": vehicle.replace("mass_kg: 1.15", "mass_kg: -1.15"),
            "weak_vehicle.yaml": re.sub(r"max_thrust_n: [0-9.]+", "max_thrust_n: 2.0", vehicle),
        }
        # One bad key a file: the stack's blocks, the sensors, the simulation, the metrics, the
        # missions, the world, the faults and the start.
        stack_cases = {
            "controller": "controller: pid", "nmpc_horizon": "controller: nmpc\n  nmpc: {horizon_steps: 0}",
            "nmpc_horizon_big": "nmpc: {horizon_steps: 500}", "nmpc_q_attitude": "nmpc: {q_attitude: [1, 2, 3]}",
            "nmpc_step": "nmpc: {step_s: -0.05}", "nmpc_typo": "nmpc: {horizon: 20}",
            "nominal_kp": "nominal: {kp_position: -1}", "nominal_tilt": "nominal: {max_tilt_rad: 3}",
            "passive_nan": "passive: {k_tilt: .nan}", "indi_cutoff": "controller: indi\n  indi: {filter_cutoff_hz: 150}",
            "indi_cutoff_rate": "controller: indi\n  control_rate_hz: 100\n  indi: {filter_cutoff_hz: 60}",
            "fdd": "fdd: magic", "composite": "fdd: composite\n  composite_fdd: {motor_index_threshold: -1}",
            "composite_samples": "composite_fdd: {motor_index_samples: 0}",
            "composite_typo": "composite_fdd: {gamma_m: 0.2}",
            "supervisor": "supervisor: {max_speed_m_s: 0}", "supervisor_rotors": "supervisor: {max_failed_rotors: 99}",
            "planner_rate": "planner: {rate_hz: -1}", "planner_weights": "planner: {weights: {time: 1, speed: 2}}",
            "planner_band": "planner: {altitude_band_m: [2, 1]}", "planner_word": "planner: magic",
            "planner_method": "planner: {method: astar}", "planner_clearance": "planner: {post_failure_clearance_m: -1}",
            "planner_factor": "planner: {post_failure_safety_factor: 2}",
            "flatness_angle": "flatness: {theta_max_deg: 95}", "flatness_hold": "flatness: {min_hold_s: 40, max_hold_s: 30}",
            "map_stride": "map: {clearing_stride: 99}", "map_resolution": "map: {resolution_m: 0}",
            "map_odds": "map: {log_odds_hit: -1}", "known_fault_rotor": "known_faults: [{rotor: 9, at_time_s: 1}]",
            "known_fault_time": "known_faults: [{rotor: 1, at_time_s: -1}]", "known_faults_map": "known_faults: {rotor: 1}",
            "control_rate": "control_rate_hz: 5000", "control_rate_nan": "control_rate_hz: .inf",
            "assembly_realloc": "assembly: {reallocation: some}", "typo": "nmcp: {}", "deskew": "deskew_frames: maybe",
        }
        for key, text in stack_cases.items():
            files[f"stack_{key}.yaml"] = no_stack + "\nstack:\n  " + text + "\n"
        other_cases = {
            "imu_rate": "sensors:\n  imu: {rate_hz: 0}", "imu_typo": "sensors:\n  imu: {rate: 100}",
            "esc_rate": "sensors:\n  esc: {rate_hz: 5000}", "lidar_rate": "sensors:\n  lidar: {frame_rate_hz: -1}",
            "lidar_off": "sensors:\n  lidar: {enabled: false, points_per_s: 0}",
            "outage": "sensors:\n  odometry: {outages: [{start_s: -1, duration_s: 1}]}",
            "sensor_typo": "sensors:\n  gps: {}", "physics": "sim: {physics_rate_hz: 10}",
            "log_rate": "sim: {log_rate_hz: 5000}", "wind_typo": "wind: {gusts: 1}",
            "tracking_start": "metrics: {tracking_start_s: 20}",
            "tracking_window": "metrics: {tracking_start_s: 5, tracking_end_s: 5}",
            "success_error": "metrics: {success_error_m: 0}", "tilt": "metrics: {recovered_tilt_rad: 2}",
            "box": "world:\n  boxes: [{center_m: [1, 1, 1], size_m: [1, 0, 1]}]",
            "cylinder": "world:\n  cylinders: [{center_m: [1, 1, 1], radius_m: 0.2, height_m: 2}]",
            "moving": "world:\n  moving_boxes: [{size_m: [1, 1, 1], waypoints_m: [], speed_m_s: 1}]",
            "world_typo": "world:\n  trees: []",
            "fault_kind": "faults: [{rotor: 0, kind: melted, onset: {at_time_s: 1}}]",
            "fault_eta": "faults: [{rotor: 0, kind: motor_stop, eta: 0.5, onset: {at_time_s: 1}}]",
            "fault_onset": "faults: [{rotor: 0, kind: motor_stop, onset: {at_time_s: 1, at_altitude_m: 2}}]",
            "fault_takeoff": "faults: [{rotor: 0, kind: motor_stop, onset: {during_takeoff_s: 0.1}}]",
            "fault_late": "faults: [{rotor: 0, kind: motor_stop, onset: {at_time_s: 99}}]",
            "fault_intermittent": "faults: [{rotor: 0, kind: motor_stop, onset: {at_time_s: 1}, intermittent: {on_s: 0.0001, off_s: 1}}]",
        }
        for key, text in other_cases.items():
            files[f"other_{key}.yaml"] = hover + "\n" + text + "\n"
        mission_cases = {
            "type": "type: cruise", "lemniscate": "type: lemniscate\n  size_m: [6, 3, 1]",
            "lemniscate_low": "type: lemniscate\n  max_speed_m_s: 1\n  center_m: [0, 0, 0.2]",
            "circle": "type: circle\n  center_m: [0, 0, 1]\n  radius_m: 1", "takeoff": "type: takeoff\n  altitude_m: -1",
            "waypoints": "type: waypoints\n  waypoints_m: []\n  max_speed_m_s: 1",
            "navigate": "type: navigate\n  waypoints_m: [[1, 0, 1]]",
            "navigate_rounds": "type: navigate\n  waypoints_m: [[1, 0, 1]]\n  rounds: 0",
            "assembly_plan": "type: assembly_plan\n  goal_m: [1, 0, 1]", "typo": "type: hover\n  positon_m: [0, 0, 1]",
        }
        for key, text in mission_cases.items():
            files[f"mission_{key}.yaml"] = no_mission + "\nmission:\n  " + text + "\n"
        files["initial_below.yaml"] = hover.replace("position_m: [0.0, 0.0, 1.0]", "position_m: [0.0, 0.0, -1.0]")
        files["both_vehicle_assembly.yaml"] = hover + "\nassembly: x.yaml\n"
        for name, text in files.items():
            with open(os.path.join(bad, name), "w") as f:
                f.write(text)
        # A vehicle file that points a scenario at the bad vehicles.
        with open(os.path.join(bad, "weak_scenario.yaml"), "w") as f:
            f.write(hover.replace(vehicle_file, "weak_vehicle.yaml"))
        os.makedirs(os.path.join(bad, "empty_dir"), exist_ok=True)
        cases = [
            [],
            ["frobnicate"],
            ["run"],
            ["run", "no/such/file.yaml"],
            ["run", bad],
            ["run", "configs/scenarios/hover.yaml", "--set", "duration_s=nan"],
            ["run", "configs/scenarios/hover.yaml", "--set", "duration_s=1e999"],
            ["run", "configs/scenarios/hover.yaml", "--set", "nosuch.key=1"],
            ["run", "configs/scenarios/hover.yaml", "--set", "vehicle.mass_kg=-1"],
            ["run", "configs/scenarios/hover.yaml", "--set", "vehicle.nosuch=1"],
            ["run", "configs/scenarios/hover.yaml", "--set", "novalue"],
            ["run", "configs/scenarios/hover.yaml", "--seed", "-1"],
            ["run", "configs/scenarios/hover.yaml", "--seed", "1e3"],
            ["run", "configs/scenarios/hover.yaml", "--log-format", "xml"],
            ["run", "configs/scenarios/hover.yaml", "--bogus"],
            ["report"],
            ["report", os.path.join(bad, "empty_dir")],
            ["report", "no/such/dir"],
            ["validate", "no/such/file.yaml"],
            ["fdd-calibrate", os.path.join(bad, "empty_dir")],
            ["fdd-calibrate", "--margin", "1", os.path.join(bad, "empty_dir")],
            ["fdd-calibrate", "--margin", "nan", os.path.join(bad, "empty_dir")],
            ["bench"],
            ["bench", "sim", "--duration", "inf"],
            ["bench", "sim", "--duration", "0"],
            ["bench", "sim", "--repetitions", "0"],
            ["bench", "sim", "--scenario", "no/such.yaml"],
            ["bench", "qp"],
            ["bench", "qp", "--instance", "no/such.json"],
            ["bench", "qp", "--instance", os.path.join(bad, "not_yaml.yaml")],
            ["bench", "ftc", "--trials", "0"],
            ["bench", "ftc", "--methods", "rotorguard,pid"],
            ["bench", "ftc", "--jobs", "0"],
            ["bench", "ftc", "--resume"],
            ["bench", "ftc", "--shard", "1/2"],
            ["bench", "ftc", "--shard", "2/2", "--out", os.path.join(bad, "shard_out")],
            ["bench", "nav", "--kinds", "desert"],
            ["bench", "nav", "--replay", "forest"],
            ["bench", "nav", "--replay", "desert:1"],
            ["bench", "nav", "--replay", "forest:x"],
            ["bench", "mars", "--trials", "0"],
            ["bench", "planner", "--pairs", "2", "--worlds", "3"],
            ["bench", "perception", "--duration", "-1"],
            ["bench", "flatness", "--seeds", "0"],
            ["bench", "campaign", "--work", ROOT],
            ["bench", "campaign", "--spec", "no/such.yaml"],
            ["campaign"],
            ["campaign", "run", "configs/campaigns/fdd_hover.yaml"],
            ["campaign", "run", "no/such.yaml", "--out", os.path.join(bad, "c")],
            ["campaign", "run", "configs/campaigns/fdd_hover.yaml", "--out", os.path.join(bad, "c"), "--shard", "3/2"],
            ["campaign", "slurm", "configs/campaigns/fdd_hover.yaml", "--shards", "0", "--out", os.path.join(bad, "s")],
            ["campaign", "slurm", "configs/campaigns/fdd_hover.yaml", "--shards", "100000", "--out", os.path.join(bad, "s")],
            ["campaign", "slurm", "configs/campaigns/fdd_hover.yaml", "--shards", "2", "--out", os.path.join(bad, "a b")],
            ["campaign", "slurm", "configs/campaigns/fdd_hover.yaml", "--shards", "2", "--out", os.path.join(bad, "s"),
             "--partition", "a b"],
            # A shard run twice into one folder: the second needs --resume.
            ["bench", "ftc", "--trials", "1", "--methods", "none", "--out", os.path.join(bad, "twice"), "--shard", "0/9"],
            ["bench", "ftc", "--trials", "1", "--methods", "none", "--out", os.path.join(bad, "twice"), "--shard", "0/9"],
            ["bench", "ftc", "--trials", "1", "--methods", "none", "--out", os.path.join(bad, "twice"), "--shard", "9/10"],
            ["bench", "ftc", "--trials", "1", "--methods", "none", "--out", os.path.join(bad, "twice"), "--shard", "a/2"],
            ["bench", "ftc", "--trials", "1", "--methods", "none", "--out", os.path.join(bad, "many"), "--shard", "0/99"],
            ["campaign", "merge", os.path.join(bad, "twice")],
            ["campaign", "merge", os.path.join(bad, "empty_dir")],
            ["campaign", "merge", "no/such/dir"],
        ]
        for name in list(files) + ["weak_scenario.yaml"]:
            cases.append(["validate", os.path.join(bad, name)])
            if not name.startswith(("negative_mass", "weak_vehicle")):
                cases.append(["run", os.path.join(bad, name), "--out", os.path.join(bad, "out")])
        lines = []
        for args in cases:
            code, out, err = self.run(args, timeout=600)
            shown = " ".join(a.replace(self.work, "WORK") for a in args)
            err = err.replace(self.work, "WORK").replace(ROOT, "ROOT")
            # CLI11's usage text follows its one-line error; the first line is what differs between builds.
            lines.append(f"$ rotorguard {shown}\nexit {code}\n{err.strip().splitlines()[0] if err.strip() else ''}\n")
        self.write("errors.txt", "\n".join(lines))

    def make(self, qp_instance):
        if os.path.exists(self.out):
            shutil.rmtree(self.out)
        os.makedirs(self.out)
        try:
            print("scenarios", file=sys.stderr)
            self.scenarios()
            print("benchmarks", file=sys.stderr)
            self.benches(qp_instance)
            print("campaigns, validation, bad input", file=sys.stderr)
            self.campaigns()
            self.validations()
            self.bad_inputs()
            self.write("timing_keys_ignored.txt", "".join(k + "\n" for k in sorted(self.dropped)))
        finally:
            shutil.rmtree(self.work, ignore_errors=True)


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("rotorguard", help="the program to snapshot, e.g. build/bin/rotorguard")
    p.add_argument("out", help="the snapshot's folder (replaced)")
    p.add_argument("--qp-instance", help="an OCP QP instance for `bench qp` (skipped without one)")
    p.add_argument("--truth", choices=["ideal", "realistic"],
                   help="fly the scenarios that state a world, and the benchmarks, in this one")
    a = p.parse_args()
    Snapshot(a.rotorguard, a.out, a.truth).make(a.qp_instance)


if __name__ == "__main__":
    main()
