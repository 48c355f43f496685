"""The Python package against independent truths: the command line's own files for the same
scenario and seed, hand-made bad inputs, the C++ controller it copies, and Newton's law for a
command flown from Python."""
import csv
import importlib.util
import json
import math
import os
import subprocess
import sys
import threading

import numpy as np
import pytest

import rotorguard

ROOT = os.environ.get("ROTORGUARD_SOURCE_DIR", os.path.dirname(os.path.dirname(os.path.dirname(__file__))))
CLI = os.environ.get("ROTORGUARD_CLI", os.path.join(ROOT, "build", "bin", "rotorguard"))
SCENARIOS = os.path.join(ROOT, "configs", "scenarios")
FDD_HOVER = os.path.join(SCENARIOS, "fdd_hover_propeller_loss.yaml")
HOVER = os.path.join(SCENARIOS, "hover.yaml")


def without_times(summary):
    """summary.json less what the wall clock decides (run times, real-time factors, costs)."""
    timed = ("wall_time", "realtime", "cost_ms", "_ms_", "_ms", "solve_time")
    if isinstance(summary, dict):
        return {k: without_times(v) for k, v in summary.items() if not any(t in k for t in timed)}
    if isinstance(summary, list):
        return [without_times(v) for v in summary]
    return summary


def read_csv(path):
    with open(path, newline="") as f:
        rows = list(csv.reader(f))
    return rows[0], rows[1:]


def fly_cli(scenario, out, *args):
    done = subprocess.run([CLI, "run", scenario, "--out", str(out), "-q", "--no-report", *args],
                          capture_output=True, text=True, check=False)
    assert done.returncode in (0, 1, 4), done.stderr
    with open(os.path.join(out, "summary.json")) as f:
        return done.returncode, json.load(f)


def test_run_gives_the_summary_log_and_exit_code_of_the_command_line(tmp_path):
    code, cli_summary = fly_cli(FDD_HOVER, tmp_path, "--set", "duration_s=3", "--seed", "5")
    result = rotorguard.run(FDD_HOVER, set={"duration_s": 3}, seed=5)
    assert without_times(result.summary) == without_times(cli_summary)
    assert result.exit_code == code
    # The log holds the CLI's numbers exactly: log.csv writes each with %.9g.
    header, rows = read_csv(tmp_path / "log.csv")
    assert list(result.log) == header
    assert all(len(result.log[c]) == len(rows) for c in header)
    for i, name in enumerate(header):
        if name == "nmpc_ms":  # the solver's wall-clock time
            continue
        assert ["%.9g" % v for v in result.log[name]] == [r[i] for r in rows], name
    assert "mi_0" in result.log and result.log["t"].dtype == np.float64


def test_run_with_an_output_folder_writes_the_command_lines_files(tmp_path):
    fly_cli(HOVER, tmp_path / "cli", "--set", "duration_s=2")
    result = rotorguard.run(HOVER, set={"duration_s": 2.0}, out=tmp_path / "py", log=False)
    assert result.log is None
    for name in ("log.csv", "sensors.csv", "scene.json", "vehicle.yaml", "truth_vehicle.yaml"):
        assert (tmp_path / "py" / name).read_bytes() == (tmp_path / "cli" / name).read_bytes(), name
    with open(tmp_path / "py" / "summary.json") as f:
        assert without_times(json.load(f)) == without_times(result.summary)


def test_a_bad_value_in_a_file_is_a_config_error_naming_file_line_and_key(tmp_path):
    lines = open(HOVER).read().splitlines()
    at = next(i for i, line in enumerate(lines) if line.startswith("duration_s:"))
    lines[at] = "duration_s: -3.0"
    bad = tmp_path / "bad.yaml"
    bad.write_text("\n".join(lines) + "\n")
    # The vehicle file is named relative to the scenario's folder.
    (tmp_path / "bad.yaml").write_text(bad.read_text().replace("../vehicles/", os.path.join(ROOT, "configs/vehicles/")))
    with pytest.raises(rotorguard.ConfigError) as error:
        rotorguard.run(bad)
    assert error.value.file == str(bad)
    assert error.value.line == at + 1
    assert error.value.key == "duration_s"
    assert isinstance(error.value, ValueError)


def test_an_override_of_a_missing_key_is_a_config_error_naming_the_override():
    with pytest.raises(rotorguard.ConfigError) as error:
        rotorguard.load_scenario(HOVER, set={"stack.no_such_key": 1})
    assert error.value.file == "--set"
    assert error.value.key == "stack.no_such_key"


def test_overrides_take_python_values():
    scenario = rotorguard.load_scenario(HOVER, set={"duration_s": np.float64(2.5), "initial.position_m": [1.0, 2.0, 3]},
                                        seed=2**64 - 1)
    assert scenario.duration_s == 2.5 and scenario.seed == 2**64 - 1
    flight = rotorguard.Flight(scenario)
    assert list(flight.simulator.position) == [1.0, 2.0, 3.0]
    with pytest.raises(ValueError):
        rotorguard.load_scenario(HOVER, set={"duration_s": math.nan})
    with pytest.raises(ValueError):
        rotorguard.load_scenario(HOVER, seed=2**64)
    with pytest.raises(ValueError):
        rotorguard.load_scenario(HOVER, seed=-1)


def test_options_are_the_declared_keys_and_writable_through_the_loader():
    scenario = rotorguard.load_scenario(HOVER)
    options = scenario.options
    assert set(options) == {"sim", "sensors", "wind", "stack", "metrics"}
    scenario.set_options(options)  # written back unchanged: nothing changes
    assert scenario.options == options
    scenario.set_options({"stack": {"nmpc": {"q_position": np.array([50.0, 60.0, 700.0])}}})
    assert scenario.options["stack"]["nmpc"]["q_position"] == [50.0, 60.0, 700.0]
    assert scenario.options == rotorguard.load_scenario(HOVER, set={"stack.nmpc.q_position": [50, 60, 700]}).options
    with pytest.raises(rotorguard.ConfigError) as error:
        scenario.set_options({"stack": {"nmpc": {"horizon_steps": 0}}})
    assert error.value.file == "<options>"
    assert error.value.key == "stack.nmpc.horizon_steps"
    assert scenario.options["stack"]["nmpc"]["horizon_steps"] == options["stack"]["nmpc"]["horizon_steps"]


def test_a_missing_file_is_an_input_file_error(tmp_path):
    with pytest.raises(rotorguard.InputFileError) as error:
        rotorguard.run(tmp_path / "none.yaml")
    assert error.value.path == str(tmp_path / "none.yaml")
    assert isinstance(error.value, OSError)


def test_a_stepped_flight_is_the_flight_run_flies():
    whole = rotorguard.run(FDD_HOVER, set={"duration_s": 2.5}, seed=3)
    for by_physics_step in (False, True):
        flight = rotorguard.Flight(FDD_HOVER, set={"duration_s": 2.5}, seed=3)
        while not flight.done:
            flight.step() if by_physics_step else flight.step_control()
        stepped = flight.finish()
        assert without_times(stepped.summary) == without_times(whole.summary)
        for name in set(whole.log) - {"nmpc_ms"}:
            assert np.array_equal(stepped.log[name], whole.log[name]), name
        assert flight.finish() is stepped  # finishing twice gives the same result


def test_a_command_from_python_is_what_flies_and_newtons_law_holds():
    # The file's vehicle exactly (truth ideal; hover.yaml has no wind): from a hover, every rotor
    # at 1.2 times its hover thrust. The net vertical force is then 0.2 m g through the motors'
    # lag (eq. 6: first order, time constant sigma), less the rotor drag D_z v (eq. 1), so
    #   v' + k v = a (1 - exp(-t / sigma)),  a = 0.2 g,  k = D_z / m,
    # whose solution from v0 is below.
    flight = rotorguard.Flight(HOVER, set={"truth": "ideal", "duration_s": 1.0})
    model = flight.stack.model
    command = 1.2 * model["hover_thrusts_n"]
    while flight.time_s < 0.5 - 1e-9:
        flight.step_control()
    v0, t0 = flight.simulator.velocity[2], flight.time_s
    while flight.time_s < 0.75 - 1e-9:
        flight.step_control(command)
        assert np.array_equal(flight.simulator.applied_command, command)
    t = flight.time_s - t0
    a = 0.2 * model["gravity_m_s2"]
    k = model["rotor_drag_kg_s"][2] / model["mass_kg"]
    sigma = model["motor_time_constant_s"]
    v = v0 * math.exp(-k * t) + a / k * (1.0 - math.exp(-k * t)) \
        - a / (k - 1.0 / sigma) * (math.exp(-t / sigma) - math.exp(-k * t))
    assert flight.simulator.velocity[2] == pytest.approx(v, rel=0.03)


def test_a_bad_command_is_a_value_error_and_flies_nothing():
    flight = rotorguard.Flight(HOVER, set={"duration_s": 1.0})
    before = flight.time_s
    with pytest.raises(ValueError, match="one thrust per rotor"):
        flight.step_control(np.ones(3))
    with pytest.raises(ValueError, match="finite"):
        flight.step_control([1.0, math.inf, 1.0, 1.0])
    assert flight.time_s == before


def load_example(name):
    spec = importlib.util.spec_from_file_location(name, os.path.join(ROOT, "examples", "python", name + ".py"))
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_the_python_copy_of_the_nominal_controller_flies_the_lemniscate_within_a_millimetre_of_the_cpp_one():
    example = load_example("nominal_controller")
    scenario = os.path.join(SCENARIOS, "lemniscate_2ms.yaml")
    python = example.fly_with_python_controller(scenario, seed=4)
    native = rotorguard.run(scenario, seed=4)
    assert native.summary["tracking_rmse_m"] < 0.2  # a flight worth comparing
    gap = np.sqrt(sum((python.log[a] - native.log[a]) ** 2 for a in ("p_x", "p_y", "p_z")))
    assert gap.max() < 1e-3


def test_run_releases_the_gil_so_that_other_threads_run_during_a_flight():
    # Whether the main thread gets to run while another thread is inside the C++ flight: if the
    # flight held the GIL, the main thread could look at it at most once or twice (at the call's
    # entry), not thousands of times. No clock is involved.
    inside = []
    worker = threading.Thread(target=lambda: rotorguard.run(HOVER, set={"duration_s": 3}, log=False))
    worker.start()
    while worker.is_alive():
        frame = sys._current_frames().get(worker.ident)
        while frame is not None and frame.f_code.co_name != "run":
            frame = frame.f_back
        if frame is not None and frame.f_code.co_filename.endswith("__init__.py"):
            inside.append(frame.f_lineno)
    worker.join()
    assert len(inside) > 100


def test_wilson_interval_is_the_closed_form():
    # Wilson (1927): (p + z²/2n ± z sqrt(p(1-p)/n + z²/4n²)) / (1 + z²/n), z = 1.959964.
    z, n, s = 1.959963984540054, 10, 7
    p = s / n
    centre, half = p + z * z / (2 * n), z * math.sqrt(p * (1 - p) / n + z * z / (4 * n * n))
    lo, hi = rotorguard.wilson_interval(s, n)
    assert lo == pytest.approx((centre - half) / (1 + z * z / n), abs=1e-9)
    assert hi == pytest.approx((centre + half) / (1 + z * z / n), abs=1e-9)
    assert rotorguard.mcnemar_exact_p(0, 6) == pytest.approx(2 / 64)


def run_example(name, *args):
    done = subprocess.run([sys.executable, os.path.join(ROOT, "examples", "python", name + ".py"), *args],
                          capture_output=True, text=True, check=False, env=dict(os.environ, MPLBACKEND="Agg"))
    assert done.returncode == 0, done.stderr
    return done.stdout


def is_png(path):
    with open(path, "rb") as f:
        return f.read(8) == b"\x89PNG\r\n\x1a\n"


def test_the_fdd_hover_example_plots_the_indices_of_the_isolated_rotor(tmp_path):
    out = run_example("fdd_hover", "--duration", "4", "--png", str(tmp_path / "fdd.png"))
    assert "rotor 0 propeller_failed isolated at 2.0" in out
    assert is_png(tmp_path / "fdd.png")


def test_the_onset_sweep_example_plots_success_rates_with_their_intervals(tmp_path):
    out = run_example("onset_sweep", "--onsets", "0.1", "1.0", "--seeds", "2", "--duration", "4",
                      "--png", str(tmp_path / "sweep.png"))
    rows = [line.split() for line in out.splitlines() if line.strip()[:1].isdigit()]
    assert [r[0] for r in rows] == ["0.100", "1.000"]
    assert is_png(tmp_path / "sweep.png")


def test_a_campaign_run_from_python_records_what_the_command_line_records(tmp_path):
    spec = tmp_path / "sweep.yaml"
    spec.write_text(f"""name: py_sweep
scenario: {HOVER}
seed: 3
repeats: 2
grid:
  duration_s: [0.5, 1.0]
random:
  initial.yaw_rad: {{uniform: [-0.5, 0.5]}}
metrics: [success, tracking_rmse_m, max_tilt_rad]
""")
    done = subprocess.run([CLI, "campaign", "run", str(spec), "--out", str(tmp_path / "cli"), "-q"],
                          capture_output=True, text=True, check=False)
    assert done.returncode == 0, done.stderr
    ran = rotorguard.run_campaign(spec, out=tmp_path / "py", jobs=2)
    read = rotorguard.read_campaign(tmp_path / "cli")
    assert len(ran) == 4 and ran.records == read.records
    assert read.manifest["campaign"] == "py_sweep"
    table = read.table()
    assert list(table["trial"]) == [0, 1, 2, 3]
    assert sorted(set(table["params.duration_s"])) == [0.5, 1.0]
    assert table["tracking_rmse_m"].dtype == np.float64 and np.all(np.isfinite(table["tracking_rmse_m"]))
    summary = rotorguard.merge_campaign(tmp_path / "py")
    assert (tmp_path / "py" / "summary.md").exists() and summary
    # One shard of two is no whole campaign: nothing to return until the shards are merged.
    assert rotorguard.run_campaign(spec, out=tmp_path / "half", shard=(0, 2)) is None


def test_the_messages_are_what_the_sensors_read_in_a_hover():
    # In a steady hover the accelerometer reads the specific force g up (body z) and the gyroscope
    # about nothing: the messages the stack received, within their noise and the airframe's
    # vibration (docs/truth.md).
    flight = rotorguard.Flight(HOVER, set={"truth": "ideal", "duration_s": 3.0})
    while flight.time_s < 2.0:
        flight.step_control()
    forces = []
    while len(forces) < 50:
        flight.step()
        imu = flight.messages.get("imu")
        if imu is not None and (not forces or imu["t_s"] != forces[-1][0]):
            forces.append((imu["t_s"], imu["specific_force"]))
    mean = np.mean([f for _, f in forces], axis=0)
    assert mean[2] == pytest.approx(flight.stack.model["gravity_m_s2"], rel=0.03)
    assert np.linalg.norm(mean[:2]) < 0.3


def test_the_lidar_points_lie_on_the_walls_of_a_hand_made_room(tmp_path):
    # A floor (top at z = 0) and a wall (face at x = 3 m) around a hover at 1 m: every return of a
    # frame, placed in the world with the true pose at the frame's end and the sensor's mount,
    # lies on one of the two surfaces, within the range noise (2 cm) and the rotation of the
    # frame's 0.1 s.
    with open(HOVER) as f:
        text = f.read().replace("../vehicles/", os.path.join(ROOT, "configs", "vehicles") + "/")
    room = tmp_path / "room.yaml"
    room.write_text(text + "world:\n  boxes:\n"
                    "    - {center_m: [0, 0, -0.5], size_m: [100, 100, 1]}\n"
                    "    - {center_m: [3.5, 0, 2], size_m: [1, 100, 4]}\n"
                    "sensors:\n  lidar: {}\n")
    flight = rotorguard.Flight(room, set={"truth": "ideal", "duration_s": 5.0}, log=False)
    while flight.time_s < 3.0:
        flight.step_control()
    while "lidar" not in flight.messages:
        flight.step()
    frame = flight.messages["lidar"]
    points = frame["points"].astype(float)
    assert points.ndim == 2 and points.shape[1] == 3 and frame["offsets_s"].shape == (len(points),)
    assert len(points) + frame["dropped"] == 20000  # the default 200,000 pulses/s at 10 Hz
    span = frame["t_end_s"] - frame["t_start_s"]
    assert np.all((frame["offsets_s"] >= 0.0) & (frame["offsets_s"] < span)) and np.all(np.diff(frame["offsets_s"]) >= 0)
    ranges = np.linalg.norm(points, axis=1)
    elevation = np.arcsin(points[:, 2] / ranges)
    assert np.all((elevation > math.radians(-7.0) - 1e-4) & (elevation < math.radians(52.0) + 1e-4))
    truth = flight.simulator
    rotation = load_example("nominal_controller").rotation  # the attitude's matrix
    world = (rotation(truth.attitude) @ (points + [0.0, 0.0, 0.06]).T).T + truth.position
    off_surface = np.minimum(np.abs(world[:, 2]), np.abs(world[:, 0] - 3.0))
    near = ranges < 10.0
    assert near.sum() > 1000
    assert np.median(off_surface[near]) < 0.03 and off_surface[near].max() < 0.15
    assert np.percentile(off_surface, 99) < 0.3
