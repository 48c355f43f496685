"""rotorguard from Python: fly scenarios, step them with a controller of your own, read the results.

    import rotorguard
    result = rotorguard.run("configs/scenarios/fdd_hover_propeller_loss.yaml", seed=3)
    result.summary["success"], result.log["t"], result.log["mi_0"]

docs/python.md describes every function; the C++ core does the flying (rotorguard._core).
"""
import json
import math
import os

import numpy as np

from . import _core
from ._core import mcnemar_exact_p, wilson_interval
from .errors import ConfigError, CorruptFileError, Error, InputFileError

__all__ = [
    "ConfigError",
    "CorruptFileError",
    "Error",
    "CampaignRecords",
    "Flight",
    "InputFileError",
    "RunResult",
    "load_scenario",
    "mcnemar_exact_p",
    "merge_campaign",
    "read_campaign",
    "run",
    "run_campaign",
    "wilson_interval",
]

# The command line's exit codes (docs/cli.md) of a flight's outcome.
EXIT_SUCCESS, EXIT_FAILED, EXIT_INFEASIBLE = 0, 1, 4


def _value_text(key, value):
    """A Python value as the YAML text of an override (what `--set key=TEXT` takes)."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, int):
        return str(value)
    if isinstance(value, float):
        if not math.isfinite(value):
            raise ValueError(f"set: {key} = {value} is invalid; expected a finite number")
        return repr(value)
    if isinstance(value, str):
        return value
    if isinstance(value, (list, tuple)):
        return "[" + ", ".join(_value_text(key, v) for v in value) + "]"
    if hasattr(value, "tolist"):  # a numpy array or scalar
        return _value_text(key, value.tolist())
    raise ValueError(f"set: {key} = {value!r} is invalid; expected a number, bool, string or list of them")


def _overrides(values):
    """{key.path: value} (or pairs) as the loader's (key, text) overrides."""
    if values is None:
        return []
    items = values.items() if isinstance(values, dict) else values
    out = []
    for item in items:
        if isinstance(item, str):
            key, eq, text = item.partition("=")
            if not eq or not key:
                raise ValueError(f"set: '{item}' is invalid; expected key.path=value")
            out.append((key, text))
            continue
        key, value = item
        out.append((str(key), _value_text(key, value)))
    return out


def _seed(seed):
    if seed is None:
        return None
    if isinstance(seed, bool) or not isinstance(seed, int) or not 0 <= seed < 2**64:
        raise ValueError(f"seed: {seed!r} is invalid; expected an integer in [0, 2^64-1]")
    return seed


def load_scenario(scenario, set=None, seed=None):
    """Loads and validates a scenario file (YAML), with `set` overrides ({"duration_s": 5,
    "faults.0.rotor": 2, "vehicle.mass_kg": 1.2}: any key `rotorguard keys` lists) and `seed`
    (overrides the file's). Raises ConfigError (with file, line and key) or InputFileError."""
    if isinstance(scenario, _core.Scenario):
        if set:
            raise ValueError("set: a loaded scenario takes no overrides; pass them to load_scenario")
        loaded = scenario
    else:
        loaded = _core.load_scenario(os.fspath(scenario), _overrides(set))
    seed = _seed(seed)
    if seed is not None:
        loaded.seed = seed
    return loaded


class RunResult:
    """A finished flight: `summary` (summary.json's dict), `log` ({column: numpy array} at the
    scenario's log rate; docs/scenarios.md, "Outputs"), `success`, and `exit_code` (what
    `rotorguard run` would exit with: 0 success, 1 failed, 4 a waypoint unreachable)."""

    def __init__(self, summary, log, success, infeasible, out):
        self.summary = summary
        self.log = log
        self.success = success
        self.exit_code = EXIT_INFEASIBLE if infeasible else (EXIT_SUCCESS if success else EXIT_FAILED)
        self.out = out

    def __repr__(self):
        outcome = "success" if self.success else "failed: " + str(self.summary.get("failure_reason"))
        return f"<rotorguard.RunResult {self.summary.get('scenario')!r} seed {self.summary.get('seed')}: {outcome}>"


def run(scenario, set=None, seed=None, out=None, log=True, log_format="csv", report=False,
        stop_when_mission_complete=False):
    """Flies a scenario to its end, as `rotorguard run` does, and returns a RunResult.

    scenario: a file path or a loaded scenario (load_scenario). set, seed: as load_scenario.
    out: a folder to write the run's files to (summary.json, log.csv, ...; none by default).
    log: keep the log's columns in memory (result.log). The flight runs without the GIL, so
    threads can fly several at once."""
    loaded = load_scenario(scenario, set, seed)
    out_dir = None if out is None else os.fspath(out)
    summary, columns, success, infeasible = _core.run(loaded, out_dir, log_format, report, log,
                                                      stop_when_mission_complete)
    return RunResult(summary, columns if log else None, success, infeasible, out_dir)


class Flight:
    """A flight stepped from Python.

        flight = rotorguard.Flight("configs/scenarios/hover.yaml")
        while not flight.done:
            estimate = flight.stack.estimate       # what the stack believes
            flight.step_control(my_thrusts(estimate, flight.stack.reference))
        result = flight.finish()

    `stack` is the flight stack's view (estimate, reference, command, mode, fdd, nmpc, model);
    `simulator` is the truth (state, rotor thrusts, faults), which the stack never sees;
    `messages` are the sensor messages the stack received in the latest step."""

    def __init__(self, scenario, set=None, seed=None, out=None, log=True, log_format="csv", report=False,
                 stop_when_mission_complete=False):
        self.scenario = load_scenario(scenario, set, seed)
        self._out = None if out is None else os.fspath(out)
        self._log = log
        self._flight = _core.Flight(self.scenario, self._out, log_format, report, log, stop_when_mission_complete)
        self._result = None

    @property
    def done(self):
        """True once the flight reached its duration or crashed."""
        return self._flight.done

    @property
    def time_s(self):
        return self._flight.time_s

    @property
    def stack(self):
        return self._flight.stack

    @property
    def simulator(self):
        return self._flight.simulator

    @property
    def messages(self):
        return self._flight.messages

    def step(self):
        """One physics step (the stack's control cycle first when one is due); False once done."""
        return self._flight.step()

    def step_control(self, command=None):
        """The rest of the control period: the flight stands at a control instant whose cycle the
        stack has run (its estimate and reference are the controller's inputs); with `command`
        (one thrust per rotor [N]) that command flies instead of the stack controller's, and the
        stack's fault detection sees it as sent. Then the physics to the next instant and its
        cycle. False once done."""
        return self._flight.step_control(command)

    def fly(self):
        """Steps to the end, without the GIL."""
        self._flight.fly()

    def finish(self):
        """Ends the flight where it stands and returns its RunResult (files written when `out`)."""
        if self._result is not None:
            return self._result
        summary, success, infeasible = self._flight.finish()
        log = self._flight.take_log() if self._log else None
        self._result = RunResult(summary, log, success, infeasible, self._out)
        return self._result


class CampaignRecords:
    """A campaign's trial records (docs/campaigns.md, "Results"): `records` is the list of dicts
    of results.jsonl in trial order ({"trial", "id", "status", "params", "metrics", "message"});
    `manifest` the first shard's manifest (None for a campaign just run); `table()` the same as a
    numpy structured array."""

    def __init__(self, records, manifest=None):
        self.records = records
        self.manifest = manifest

    def __len__(self):
        return len(self.records)

    def table(self):
        """One row per trial: `trial`, `status`, `message`, then each parameter (`params.KEY`) and
        each metric, as float64 where every value is a number, a bool or null (null: NaN), else as a
        string (a word, such as a re-planning decision)."""
        params = sorted({k for r in self.records for k in r.get("params", {})})
        metrics = sorted({k for r in self.records for k in r.get("metrics", {})})
        columns = [("trial", [r["trial"] for r in self.records]), ("status", [r["status"] for r in self.records]),
                   ("message", [r.get("message", "") for r in self.records])]
        columns += [("params." + k, [_number_or_text(r.get("params", {}).get(k)) for r in self.records])
                    for k in params]
        columns += [(k, [r.get("metrics", {}).get(k) for r in self.records]) for k in metrics]
        fields, values = [], []
        for name, column in columns:
            if all(v is None or isinstance(v, (bool, int, float)) for v in column):
                fields.append((name, np.int64 if name == "trial" else np.float64))
                values.append([math.nan if v is None else v for v in column])
            else:
                width = max(1, max(len(str(v)) for v in column))
                fields.append((name, f"U{width}"))
                values.append(["" if v is None else str(v) for v in column])
        table = np.zeros(len(self.records), dtype=fields)
        for (name, _), column in zip(fields, values):
            table[name] = column
        return table


def _number_or_text(text):
    """A parameter as recorded (text): a number when it reads as one."""
    if text is None:
        return None
    try:
        return float(text)
    except ValueError:
        return text


def run_campaign(spec, out=None, jobs=1, shard=(0, 1), resume=False, trial_timeout=100.0):
    """Runs a campaign spec (configs/campaigns/*.yaml, a sweep or a benchmark's) as `rotorguard
    campaign run` does: `jobs` threads, shard (index, count), `resume` a folder's unfinished
    results, each trial under the watchdog (stopped past `trial_timeout` wall-clock seconds per
    simulated second; 0: unwatched). `out` keeps the results folder (default: a temporary one).
    Returns the CampaignRecords of the whole campaign, or None for one shard of several (merge
    the folders when every shard is done)."""
    index, count = shard
    out_dir = None if out is None else os.fspath(out)
    records = _core.run_campaign(os.fspath(spec), out_dir, jobs, index, count, resume, float(trial_timeout))
    return None if records is None else CampaignRecords(json.loads(records))


def read_campaign(*dirs):
    """The records of a finished campaign from its results folders (every shard's), checked as
    `campaign merge` checks them: every trial once, one spec, one program."""
    records, manifest = _core.read_campaign([os.fspath(d) for d in dirs])
    return CampaignRecords(json.loads(records), json.loads(manifest))


def merge_campaign(*dirs, out=None):
    """`rotorguard campaign merge`: writes summary.json and summary.md (and a benchmark's
    bench.json and bench.md) into `out` (default: the first folder); returns the summary."""
    folders = [os.fspath(d) for d in dirs]
    return json.loads(_core.merge_campaign(folders, folders[0] if out is None else os.fspath(out)))
