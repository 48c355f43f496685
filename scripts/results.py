#!/usr/bin/env python3
"""make results: runs the published benchmarks and writes docs/results.md from their records.

    scripts/results.py [--build build] [--source DIR] [--out out/results] [--only NAME ...]
                       [--render-only] [--pack | --pack-only] [--records results/records.tar.xz]
    scripts/results.py --self-test

Each job is one `rotorguard bench ...` or `rotorguard campaign run ...` command whose trial records
(results.jsonl) land in OUT/NAME, a set of `rotorguard run` flights (their summaries), or the
threshold calibration (two campaigns, sixteen runs and `rotorguard fdd-calibrate`). A job whose folder already holds its finished result is not run
again (delete the folder to rerun it; an unfinished one is resumed), so the page can be rendered
from jobs run at different times on one build. Every figure of docs/results.md is computed here
from the trial records: rates with their 95 % Wilson intervals, means with their 95 % normal
intervals. The page names each table's command, world and the machine (CPU model) it ran on; the
README's block between `<!-- BEGIN results -->` and `<!-- END results -->` is written from the same
figures, and a test (tests/docs) fails when README quotes a number the page does not hold.

The whole run takes several hours on a 2-core machine, so its records travel with the repository:
 `--pack` (after the jobs) or `--pack-only` (at once; stop a running `make results` first)
writes OUT into RECORDS, a reproducible tar.xz (the flights' logs left out, an unfinished calibration
left out whole), and a later run whose OUT holds no job yet starts from RECORDS. A job resumes only
with a build of the revision that began it (`campaign run --resume` refuses another): build that
revision in a checkout of its own (`git worktree add ../rg REV`, then `make -C ../rg configure &&
cmake --build ../rg/build --target rotorguard_cli`) and pass `--build ../rg/build --source ../rg`,
so that the jobs fly that revision's configs; the page is written here.
"""
import argparse
import datetime
import json
import math
import os
import re
import subprocess
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
# The checkout whose configs the jobs fly and whose build runs them (--source; by default this one).
SOURCE = ROOT
RECORDS = os.path.join(ROOT, 'results', 'records.tar.xz')
Z95 = 1.959963984540054

# The FTC benchmark's cells flown at 1000 trials: the single complete failures (Tables III and IV),
# the second failures and the fault-free cells (the false-alarm rate).
FTC_CELLS = ('hover/propeller_loss,hover/motor_stop,tracking/propeller_loss,tracking/motor_stop,'
             'takeoff/propeller_loss,takeoff/motor_stop,hover/motor_stop_then_twin,'
             'hover/motor_stop_then_adjacent,hover/motor_stop_then_adjacent_parachute,hover/none,tracking/none,'
             'takeoff/none,hover/propeller_loss_battery_full,hover/propeller_loss_battery_30,'
             'tracking/propeller_loss_battery_full,tracking/propeller_loss_battery_30,'
             'takeoff/propeller_loss_ground_effect,takeoff/motor_stop_ground_effect')

# name, kind, arguments after `rotorguard`, what it measures
JOBS = [
    ('ftc_rotorguard', 'bench',
     ['bench', 'ftc', '--trials', '1000', '--seed', '1', '--methods', 'rotorguard', '--truth', 'realistic',
      '--cells', FTC_CELLS],
     'rotorguard on paper 000\'s FTC benchmark'),
    ('ftc_baselines', 'bench',
     ['bench', 'ftc', '--trials', '100', '--seed', '1', '--methods', 'fixedtime,indi', '--truth', 'realistic',
      '--cells', FTC_CELLS],
     'the baselines on the same cells'),
] + [
    ('mars_' + w, 'bench', ['bench', 'mars', '--trials', '100', '--seed', '1', '--truth', w],
     'paper 002\'s benchmark (Tables I and II, the allocation\'s time, the self-reconfiguration), %s' % w)
    for w in ('realistic', 'ideal')
] + [
    ('far_' + s, 'campaign', ['campaign', 'run', 'configs/campaigns/fdd_far_%s.yaml' % s], d)
    for s, d in (('takeoff', '1000 take-offs to 1.5 m and a hover, 10 s'),
                 ('landing', '1000 hovers at 1.5 m and landings, 10 s'),
                 ('takeoff_ground_effect', 'the take-offs with the rotors\' ground effect'),
                 ('landing_ground_effect', 'the landings with the rotors\' ground effect'),
                 ('landing_ground_effect_strong', 'the landings with twice that ground effect'),
                 ('emergency_landing', '1000 hovers whose odometry is lost for 1 s, landed by the supervisor, 12 s'),
                 ('lemniscate', '1000 flights of 60 s of the 2 m/s lemniscate, gusts 0-0.5 m/s'),
                 ('lemniscate_3ms', '1000 flights of 60 s of the lemniscate at 3 m/s, gusts 0-0.5 m/s'),
                 ('gusts', '1000 flights of 60 s of the 2 m/s lemniscate in gusts of 0-1.5 m/s std'))
]


# Post-failure tracking: paper 000's 1 m/s lemniscate with propeller 0 lost, as shipped (drawn
# delays, the stack expecting 3 ms), and the same with the true delay fixed at 3.5 ms (2.5 ms of
# computation and 1 ms of ESC latency) while the NMPC assumes none, half, all or twice of it.
TRACKING_SCENARIO = 'configs/scenarios/nmpc_lemniscate_1ms_rotor0_failed.yaml'
TRACKING_SEEDS = list(range(1, 21))
FIXED_DELAY = ['truth.computation_delay_min_s=0.0025', 'truth.computation_delay_max_s=0.0025',
               'truth.esc_command_latency_min_s=0.001', 'truth.esc_command_latency_max_s=0.001']
ASSUMED_DELAYS = [0.0, 0.00175, 0.0035, 0.007]
# A `runs` job: flights of `rotorguard run SCENARIO --seed K [--set ...]`, two at a time, each
# kept as its summary.json (the logs are deleted once read). Entries: (label, scenario, seed, sets).
RUN_JOBS = {
    'nmpc_tracking': [('seed%d' % k, TRACKING_SCENARIO, k, []) for k in TRACKING_SEEDS],
    'nmpc_delay': [('seed%d_assumed%g' % (k, d * 1000), TRACKING_SCENARIO, k,
                    FIXED_DELAY + ['stack.command_delay_s=%g' % d])
                   for d in ASSUMED_DELAYS for k in TRACKING_SEEDS],
}
JOBS += [('nmpc_tracking', 'runs', ['run', TRACKING_SCENARIO, '--seed', 'K'],
          '20 seeds of the 1 m/s lemniscate with propeller 0 lost'),
         ('nmpc_delay', 'runs', ['run', TRACKING_SCENARIO, '--seed', 'K', '--set', 'truth.computation_delay_min_s=0.0025',
                                 '--set', 'truth.computation_delay_max_s=0.0025', '--set',
                                 'truth.esc_command_latency_min_s=0.001', '--set', 'truth.esc_command_latency_max_s=0.001',
                                 '--set', 'stack.command_delay_s=D'],
          'the same 20 seeds with a true delay of 3.5 ms, the NMPC assuming D = 0, 1.75, 3.5 or 7 ms')]

# Every shipped scenario at 50 seeds no test or document flies (ctest flies 1-3), in the realistic
# world and, beside it, the ideal one (what the realistic world costs). The scenarios written to show a
# failure succeed when they show it: the same words tests/harness/shipped_scenarios_test.cc
# (IntendedFailures) checks for.
SHIPPED_SEEDS = list(range(1001, 1051))
INTENDED_FAILURES = {'hover_motor_stop_nominal': 'crash', 'fdd_hover_second_failure': 'flight termination',
                     'emergency_landing': 'emergency landing'}


def shipped_scenarios():
    """(name, path relative to ROOT, stated world) of configs/scenarios/*.yaml."""
    out = []
    folder = os.path.join(SOURCE, 'configs', 'scenarios')
    for f in sorted(os.listdir(folder)):
        if not f.endswith('.yaml'):
            continue
        world = 'realistic'
        with open(os.path.join(folder, f)) as fh:
            for line in fh:
                if line.startswith('truth:'):
                    world = 'ideal' if 'ideal' in line.split('#', 1)[0] else 'realistic'
        out.append((f[:-5], 'configs/scenarios/' + f, world))
    return out


def shipped_flights():
    return [('%s_%s_seed%d' % (name, w, k), path, k, ['truth=%s' % w])
            for name, path, stated in shipped_scenarios()
            for w in ('realistic', 'ideal')
            for k in SHIPPED_SEEDS]
JOBS += [('shipped', 'runs', ['run', 'configs/scenarios/NAME.yaml', '--seed', 'K', '--set', 'truth=WORLD'],
          'every shipped scenario at seeds 1001-1050')]


# The calibration of the composite FDD's thresholds, on flights apart from every evaluation above:
# the two calibration campaigns (their own seed streams) and 16 faulty runs (a motor stop and a
# propeller loss, in hover and at take-off, on each rotor, each its own vehicle: run seeds
# 111-144), through `rotorguard fdd-calibrate`. The page sets its suggestions beside the shipped
# thresholds and checks that no evaluation set shares a vehicle with it.
CALIBRATION_CAMPAIGNS = ['fdd_calibration_lemniscate', 'fdd_calibration_takeoff']
CALIBRATION_RUNS = [run for r in range(4) for run in (
    ('hover_motor_%d' % r, 'configs/scenarios/fdd_hover_motor_stop.yaml', 111 + r, ['faults.0.rotor=%d' % r]),
    ('hover_propeller_%d' % r, 'configs/scenarios/fdd_hover_propeller_loss.yaml', 121 + r, ['faults.0.rotor=%d' % r]),
    ('takeoff_propeller_%d' % r, 'configs/scenarios/fdd_takeoff_propeller_loss.yaml', 131 + r,
     ['faults.0.rotor=%d' % r, 'truth=realistic']),
    ('takeoff_motor_%d' % r, 'configs/scenarios/fdd_takeoff_propeller_loss.yaml', 141 + r,
     ['faults.0.rotor=%d' % r, 'faults.0.kind=motor_stop', 'truth=realistic']))]
JOBS += [('calibration', 'calibration', ['fdd-calibrate', 'runs/*', '--healthy'] + CALIBRATION_CAMPAIGNS,
          'the thresholds calibrated on the calibration sets')]


# Side by side with the peers (docs/performance.md): the drivers of benchmarks/peers/ run rotorguard's
# solver and the peer's in one process, alternated. They exist in a build configured with the peers
# (`make peers`: scripts/peers.sh, then ROTORGUARD_PEERS_DIR); the QP instance is not in the repository
# (--qp-instance). A driver runs as many times as it names, the drivers taking turns; every run is
# kept. The odometry's runs are long (7 min: 16 conditions of 200 frames), so once.
PEER_DRIVERS = [('peer_qp', ['QP_INSTANCE', '--repetitions', '3'], 3),
                ('peer_lbfgs', ['--problems', '200', '--seed', '1', '--repetitions', '3'], 3),
                ('peer_lio', ['--seed', '1', '--duration', '20'], 1)]
PEER_REPEATS = max(r for _, _, r in PEER_DRIVERS)
JOBS += [('performance', 'peers', [], 'rotorguard beside HPIPM (the NMPC\'s QP), GCOPTER\'s L-BFGS (the '
          'planner\'s optimiser) and KISS-ICP (the odometry)')]


def cmake_cache(build):
    """The build's CMake cache as a dict (empty when there is none)."""
    out = {}
    try:
        with open(os.path.join(build, 'CMakeCache.txt')) as f:
            for line in f:
                m = re.match(r'([A-Za-z0-9_]+):[A-Z]+=(.*)', line.rstrip('\n'))
                if m:
                    out[m.group(1)] = m.group(2)
    except OSError:
        pass
    return out


def run_peers(build, folder, qp_instance):
    """The peer drivers' runs into folder (peer_qp.K.json, peer_lbfgs.K.json) and its manifest.json; a
    clear word, and nothing run, when the build has no drivers or no instance was given."""
    cache = cmake_cache(build)
    peers_dir = cache.get('ROTORGUARD_PEERS_DIR', '')
    drivers = [os.path.join(build, 'bin', d) for d, _, _ in PEER_DRIVERS]
    if not peers_dir or not all(os.access(d, os.X_OK) for d in drivers):
        print('results: performance: skipped: %s has no peer drivers (make peers; docs/performance.md)' % build,
              flush=True)
        return
    if not qp_instance:
        print('results: performance: skipped: no --qp-instance FILE (the NMPC\'s reference QP)', flush=True)
        return
    try:
        with open(os.path.join(peers_dir, 'peers.json')) as f:
            peers = json.load(f)
    except (OSError, ValueError) as e:
        sys.exit('results: performance: %s/peers.json: %s (run scripts/peers.sh %s again)' % (peers_dir, e, peers_dir))
    os.makedirs(folder, exist_ok=True)
    commands = {}
    for k in range(1, PEER_REPEATS + 1):
        for name, args, repeats in PEER_DRIVERS:
            if k > repeats:
                continue
            path = os.path.join(folder, '%s.%d.json' % (name, k))
            # The instance is named by its file name, run from its folder: the records hold no path of
            # this machine.
            cwd = os.path.dirname(os.path.abspath(qp_instance)) if 'QP_INSTANCE' in args else None
            args = [os.path.basename(qp_instance) if a == 'QP_INSTANCE' else a for a in args]
            commands[name] = ' '.join(['build/bin/' + name] + args)
            if os.path.exists(path):
                continue
            print('results: performance: %s, run %d of %d' % (name, k, repeats), flush=True)
            done = subprocess.run([os.path.abspath(os.path.join(build, 'bin', name))] + args, capture_output=True,
                                  text=True, cwd=cwd)
            if done.returncode != 0:
                sys.exit('results: performance: %s failed (exit %d): %s' % (name, done.returncode, done.stderr.strip()))
            with open(path + '.partial', 'w') as f:
                f.write(done.stdout)
            os.replace(path + '.partial', path)
    flags = ' '.join(x for x in (cache.get('CMAKE_CXX_FLAGS_RELEASE', ''),
                                 '-march=x86-64-v3' if cache.get('ROTORGUARD_X86_64_V3') == 'ON'
                                 and cache.get('ROTORGUARD_HAS_X86_64_V3') == '1' else '') if x)
    with open(os.path.join(folder, 'manifest.json'), 'w') as f:
        json.dump({'version': program_version(os.path.join(build, 'bin', 'rotorguard')), 'cpu': cpu_model(),
                   'cores': os.cpu_count(), 'compiler': cache.get('CMAKE_CXX_COMPILER', ''),
                   'rotorguard_flags': flags, 'peers': peers, 'commands': commands,
                   'finished': datetime.datetime.now().strftime('%Y-%m-%d %H:%M')}, f, indent=1)


def run_calibration(binary, folder):
    """The calibration campaigns and faulty runs (their logs kept: fdd-calibrate replays them)."""
    for c in CALIBRATION_CAMPAIGNS:
        out = os.path.join(folder, c)
        if not os.path.exists(os.path.join(out, 'summary.json')):
            run_job(binary, c, 'campaign', ['campaign', 'run', 'configs/campaigns/%s.yaml' % c], out)
    runs = []
    for label, scenario, seed, sets in CALIBRATION_RUNS:
        runs.append(os.path.join(folder, 'runs', label))
        fly(binary, runs[-1], scenario, seed, sets)
    cmd = [binary, 'fdd-calibrate'] + runs
    for c in CALIBRATION_CAMPAIGNS:
        cmd += ['--healthy', os.path.join(folder, c)]
    subprocess.run(cmd + ['--out', os.path.join(folder, 'calibration')], cwd=SOURCE, check=True,
                   stdout=subprocess.DEVNULL)


def fly(binary, out, scenario, seed, sets):
    """One flight into `out`, unless its summary is there; returns the summary (None when it wrote none)."""
    if not os.path.exists(os.path.join(out, 'summary.json')):
        cmd = [binary, 'run', scenario, '--seed', str(seed), '-q', '--no-report', '--out', out]
        for kv in sets:
            cmd += ['--set', kv]
        subprocess.run(cmd, cwd=SOURCE, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    path = os.path.join(out, 'summary.json')
    if not os.path.exists(path):
        return None
    with open(path) as f:
        return json.load(f)


def run_flights(binary, name, folder, workers=2):
    """Flies RUN_JOBS[name], two flights at a time, keeps each flight's figures in folder/done.json."""
    from concurrent.futures import ThreadPoolExecutor
    os.makedirs(folder, exist_ok=True)
    jobs = RUN_JOBS[name]

    def one(job):
        label, scenario, seed, sets = job
        out = os.path.join(folder, label)
        summary = fly(binary, out, scenario, seed, sets)
        row = dict(label=label, scenario=scenario, seed=seed, sets=sets, success=bool(summary and summary['success']),
                   failure_reason=(summary or {}).get('failure_reason') or ('no summary' if summary is None else ''))
        if summary is not None and name != 'shipped':
            row.update(truth_vs_ref=summary['tracking_rmse_m'], est_vs_truth=summary['estimate_position_rmse_m'],
                       est_vs_ref=estimate_vs_reference(out, summary))
        if summary is not None:
            for f in os.listdir(out):  # the figures are read: keep the summary, not the logs
                if f != 'summary.json' and os.path.isfile(os.path.join(out, f)):
                    os.remove(os.path.join(out, f))
        return row

    rows = []
    with ThreadPoolExecutor(max_workers=workers) as pool:
        for i, row in enumerate(pool.map(one, jobs)):
            rows.append(row)
            if (i + 1) % 50 == 0 or i + 1 == len(jobs):
                print('results: %s: %d of %d flights' % (name, i + 1, len(jobs)), flush=True)
    with open(os.path.join(folder, 'done.json'), 'w') as f:
        json.dump({'version': program_version(binary), 'flights': rows}, f, indent=1)


def program_version(binary):
    """What `rotorguard --version` says: the release and the revision it was built from."""
    return subprocess.run([binary, '--version'], capture_output=True, text=True).stdout.strip() or 'unknown'


def load_flights(folder):
    """(version, rows) of a runs job's done.json (older ones hold the rows alone: version None)."""
    with open(os.path.join(folder, 'done.json')) as f:
        done = json.load(f)
    if isinstance(done, list):
        return None, done
    return done['version'], done['flights']


def built(version):
    """' (rotorguard VERSION)' when the build is known."""
    return ' (rotorguard %s)' % version if version else ''



def estimate_vs_reference(folder, summary):
    """RMS of the stack's position estimate against the reference over the tracking window (log.csv)."""
    import csv
    start = summary['tracking_window_s'][0]
    sq, n = 0.0, 0
    with open(os.path.join(folder, 'log.csv')) as f:
        for r in csv.DictReader(f):
            if float(r['t']) < start:
                continue
            sq += sum((float(r['est_p_' + a]) - float(r['ref_p_' + a])) ** 2 for a in 'xyz')
            n += 1
    return math.sqrt(sq / n) if n else float('nan')


def wilson(k, n):
    if n <= 0:
        return (0.0, 1.0)
    p = k / n
    z2 = Z95 * Z95
    denom = 1.0 + z2 / n
    centre = (p + z2 / (2 * n)) / denom
    half = Z95 * math.sqrt(p * (1 - p) / n + z2 / (4 * n * n)) / denom
    return (max(0.0, centre - half), min(1.0, centre + half))


def pct(k, n):
    """'99.9 % [99.4, 100.0]' for k of n."""
    if n == 0:
        return '/'
    lo, hi = wilson(k, n)
    # A rate or bound below 1 % keeps its second decimal: 2 of 5000 is not 0.0 %, nor is 0 of 9000's
    # upper bound.
    d = 2 if (0 < k < 0.01 * n) or (k == 0 and hi < 0.001) else 1
    return '%.*f %% [%.*f, %.*f]' % (d, 100.0 * k / n, d, 100.0 * lo, d, 100.0 * hi)


def mean_ci(values, digits=3):
    if not values:
        return '/'
    n = len(values)
    m = sum(values) / n
    sd = math.sqrt(sum((v - m) ** 2 for v in values) / (n - 1)) if n > 1 else 0.0
    half = Z95 * sd / math.sqrt(n)
    return '%.*f [%.*f, %.*f]' % (digits, m, digits, m - half, digits, m + half)


def median(values):
    return percentile(values, 0.5)


def percentile(values, p):
    """Linear interpolation between the order statistics, as the benchmarks' own (core/statistics.h)."""
    v = sorted(values)
    if not v:
        return float('nan')
    position = p * (len(v) - 1)
    lo = int(math.floor(position))
    hi = min(lo + 1, len(v) - 1)
    return v[lo] + (position - lo) * (v[hi] - v[lo])


def cpu_model():
    try:
        with open('/proc/cpuinfo') as f:
            for line in f:
                if line.startswith('model name'):
                    return line.split(':', 1)[1].strip()
    except OSError:
        pass
    return 'unknown CPU'


def records(folder):
    path = os.path.join(folder, 'results.jsonl')
    out = []
    with open(path) as f:
        for line in f:
            line = line.strip()
            if line:
                out.append(json.loads(line))
    return out


def finished(kind, folder):
    if kind == 'runs':
        return os.path.exists(os.path.join(folder, 'done.json'))
    if kind == 'bench':
        return os.path.exists(os.path.join(folder, 'bench.json'))
    if kind == 'calibration':
        return os.path.exists(os.path.join(folder, 'calibration', 'calibration.json'))
    if kind == 'peers':
        return os.path.exists(os.path.join(folder, 'manifest.json'))
    return os.path.exists(os.path.join(folder, 'summary.json'))


def run_job(binary, name, kind, args, folder):
    cmd = [binary] + args + ['--out', folder]
    if os.path.isdir(folder) and os.path.exists(os.path.join(folder, 'results.jsonl')):
        cmd.append('--resume')
    print('results: %s: %s' % (name, ' '.join(cmd)), flush=True)
    # stderr passes through: the command's own error (a resume refused for another build, say) and,
    # on a terminal, its progress.
    done = subprocess.run(cmd, cwd=SOURCE, stdout=subprocess.DEVNULL)
    if done.returncode != 0:
        sys.exit('results: %s failed (exit %d); resume it with the build of the revision that began it '
                 '(see --help), or delete %s to start it again' % (name, done.returncode, folder))
    if kind == 'campaign':
        subprocess.run([binary, 'campaign', 'merge', folder], cwd=SOURCE, check=True, stdout=subprocess.DEVNULL)


def load_thresholds():
    """The shipped composite-FDD thresholds (a flat YAML map of numbers)."""
    out = {}
    with open(os.path.join(SOURCE, 'configs/vehicles/zhou2025_quad_fdd.yaml')) as f:
        for line in f:
            line = line.split('#', 1)[0].strip()
            if ':' in line:
                k, v = line.split(':', 1)
                try:
                    out[k.strip()] = float(v)
                except ValueError:
                    pass
    return out


def manifest(folder):
    with open(os.path.join(folder, 'manifest.json')) as f:
        return json.load(f)


def command_text(args):
    return 'rotorguard ' + ' '.join(args)


# --- the tables ---------------------------------------------------------------------------------

PAPER_LATENCY = {('hover', 'propeller_loss'): '0.105', ('hover', 'motor_stop'): '0.032',
                 ('tracking', 'propeller_loss'): '0.184', ('tracking', 'motor_stop'): '0.028',
                 ('takeoff', 'propeller_loss'): '0.020', ('takeoff', 'motor_stop'): '0.020'}
PAPER_SUCR = {('hover', 'propeller_loss'): '100', ('hover', 'motor_stop'): '100',
              ('tracking', 'propeller_loss'): '90', ('tracking', 'motor_stop'): '100',
              ('takeoff', 'propeller_loss'): 'ok', ('takeoff', 'motor_stop'): 'ok'}
BINS = [(0.0, 0.3), (0.3, 1.0), (1.0, 2.0), (2.0, 4.0), (4.0, 6.5)]


def metric_values(rs, key, only=None):
    """A metric's recorded values over the trials that finished (and where metric `only` holds)."""
    return [r['metrics'][key] for r in rs if r['status'] == 'ok' and r['metrics'].get(key) is not None
            and (only is None or r['metrics'].get(only))]


def ftc_cells(recs):
    cells = {}
    for r in recs:
        p = r['params']
        cells.setdefault((p['phase'], p['fault'], p['method']), []).append(r)
    return cells


def ftc_table(recs, methods):
    cells = ftc_cells(recs)
    lines = ['| phase | fault | method | trials | SucR | MDR | FAR | FDD latency mean (s) | latency max (s) | paper: SucR (%), latency (s) |',
             '|---|---|---|---|---|---|---|---|---|---|']
    summary = {}
    for (phase, fault, method), rs in cells.items():
        if (method not in methods or fault == 'none' or fault.startswith('motor_stop_then') or 'battery' in fault
                or fault.endswith('_ground_effect')):
            continue
        n = len(rs)
        ok = [r for r in rs if r['status'] == 'ok']
        success = sum(1 for r in ok if r['metrics'].get('success'))
        correct = sum(1 for r in ok if r['metrics'].get('correct'))
        false_alarm = sum(1 for r in ok if r['metrics'].get('false_alarm'))
        has_fdd = any('correct' in r['metrics'] for r in ok)
        lat = metric_values(rs, 'latency_s', 'correct')
        missed = n - correct
        lines.append('| %s | %s | %s | %d | %s | %s | %s | %s | %s | %s, %s |' % (
            phase, fault, method, n, pct(success, n), pct(missed, n) if has_fdd else '/',
            pct(false_alarm, n) if has_fdd else '/', mean_ci(lat), '%.3f' % max(lat) if lat else '/',
            PAPER_SUCR.get((phase, fault), ''), PAPER_LATENCY.get((phase, fault), '')))
        summary[(phase, fault, method)] = dict(n=n, success=success, missed=missed, lat=lat)
    return '\n'.join(lines), summary


def ftc_fault_free(recs, methods):
    cells = ftc_cells(recs)
    lines = ['| phase | method | trials | false alarms | FAR |', '|---|---|---|---|---|']
    out = {}
    for (phase, fault, method), rs in cells.items():
        if method not in methods or fault != 'none':
            continue
        n = len(rs)
        alarms = sum(1 for r in rs if r['status'] != 'ok' or r['metrics'].get('false_alarm'))
        lines.append('| %s | %s | %d | %d | %s |' % (phase, method, n, alarms, pct(alarms, n)))
        out[(phase, method)] = (alarms, n)
    return '\n'.join(lines), out


def ftc_battery(recs, methods):
    """The propeller losses flown on a battery, full and at 30 %, beside the same trials without one."""
    cells = ftc_cells(recs)
    lines = ['| phase | battery | method | trials | SucR | largest thrust at onset, median (min), × T̄ | FDD latency mean (s) |',
             '|---|---|---|---|---|---|---|']
    for phase in ('hover', 'tracking'):
        for fault, label in (('propeller_loss', 'none (the file\'s T̄ throughout)'),
                             ('propeller_loss_battery_full', 'full'), ('propeller_loss_battery_30', '30 %')):
            for method in methods:
                rs = cells.get((phase, fault, method))
                if not rs:
                    continue
                n = len(rs)
                ok = [r for r in rs if r['status'] == 'ok']
                success = sum(1 for r in ok if r['metrics'].get('success'))
                limit = metric_values(rs, 'thrust_limit_at_fault')
                lat = metric_values(rs, 'latency_s', 'correct')
                lines.append('| %s | %s | %s | %d | %s | %s | %s |' % (
                    phase, label, method, n, pct(success, n),
                    '%.3f (%.3f)' % (median(limit), min(limit)) if limit else '/', mean_ci(lat)))
    return '\n'.join(lines)


def ftc_ground_effect(recs, methods):
    """The take-off failures with the rotors' ground effect beside the same trials without it."""
    cells = ftc_cells(recs)
    lines = ['| fault | ground effect | method | trials | SucR | altitude change ≥ −0.05 m (of successes) | '
             'lowest altitude change (m) | FDD latency mean (s) |', '|---|---|---|---|---|---|---|---|']
    for fault in ('propeller_loss', 'motor_stop'):
        for cell, label in ((fault, 'none'), (fault + '_ground_effect', 'strength 1 (drawn 0.5-1.5)')):
            for method in methods:
                rs = cells.get(('takeoff', cell, method))
                if not rs:
                    continue
                n = len(rs)
                ok = [r for r in rs if r['status'] == 'ok']
                wins = [r for r in ok if r['metrics'].get('success')]
                change = metric_values(rs, 'altitude_change_m', 'success')
                held = sum(1 for c in change if c >= -0.05)
                lat = metric_values(rs, 'latency_s', 'correct')
                lines.append('| %s | %s | %s | %d | %s | %s | %s | %s |' % (
                    fault, label, method, n, pct(len(wins), n), pct(held, len(change)) if change else '/',
                    '%.3f' % min(change) if change else '/', mean_ci(lat)))
    return '\n'.join(lines)


def ftc_second(recs, methods):
    cells = ftc_cells(recs)
    lines = ['| second failure | method | trials | SucR | second isolated | second latency median / p95 (s) | '
             'false second isolations | impact speed median / p95 (m/s) | '
             + ' | '.join('onset %g-%g s after the first isolation' % b for b in BINS) + ' |',
             '|---|---|---|---|---|---|---|---|' + '---|' * len(BINS)]
    out = {}
    for (phase, fault, method), rs in cells.items():
        if method not in methods or not fault.startswith('motor_stop_then'):
            continue
        n = len(rs)
        ok = [r for r in rs if r['status'] == 'ok']
        success = sum(1 for r in ok if r['metrics'].get('success'))
        second = sum(1 for r in ok if r['metrics'].get('second_correct'))
        false2 = sum(1 for r in ok if r['metrics'].get('correct') and (r['metrics'].get('healthy_rotors_isolated') or 0) > 0)
        bins = []
        for lo, hi in BINS:
            inb = [r for r in ok if r['metrics'].get('second_after_isolation_s') is not None
                   and lo <= r['metrics']['second_after_isolation_s'] < hi]
            k = sum(1 for r in inb if r['metrics'].get('second_correct'))
            bins.append((k, len(inb)))
        latency = [r['metrics']['second_latency_s'] for r in ok
                   if r['metrics'].get('second_correct') and r['metrics'].get('second_latency_s') is not None]
        impact = [r['metrics']['crash_speed_m_s'] for r in ok if r['metrics'].get('crash_speed_m_s') is not None]
        two = lambda v, f: '%s / %s' % (f % percentile(v, 0.5), f % percentile(v, 0.95)) if v else '/'
        lines.append('| %s | %s | %d | %s | %s | %s | %d | %s | %s |' % (
            fault.replace('motor_stop_then_', '').replace('_', ', with a '), method, n, pct(success, n),
            pct(second, n), two(latency, '%.3f'), false2, two(impact, '%.2f'),
            ' | '.join('%s of %d' % (pct(k, m), m) if m else '/' for k, m in bins)))
        out[(fault, method)] = dict(n=n, second=second, false2=false2, bins=bins, impact=impact)
    return '\n'.join(lines), out


def false_second_in_single(recs):
    """Healthy rotors isolated after a correct first isolation, over the single-failure cells."""
    n = k = 0
    for r in recs:
        p = r['params']
        if p['fault'] == 'none' or p['fault'].startswith('motor_stop_then') or r['status'] != 'ok':
            continue
        if p['method'] != 'rotorguard':
            continue
        n += 1
        if r['metrics'].get('correct') and (r['metrics'].get('healthy_rotors_isolated') or 0) > 0:
            k += 1
    return k, n


MARGINS = [  # (statistic, threshold key, lower is alarming, name)
    ('fdd.healthy_extremes.debounced_motor_index', 'motor_index_threshold', True, 'motor index'),
    ('fdd.healthy_extremes.persistent_propeller_index', 'propeller_index_threshold', False, 'propeller index'),
    ('fdd.healthy_extremes.gated_takeoff_index', 'takeoff_index_threshold', False, 'take-off index'),
    ('fdd.healthy_extremes.debounced_motor_shortfall', 'motor_shortfall_threshold', False, 'motor shortfall'),
]


def far_row(name, desc, recs, thresholds):
    n = len(recs)
    ok = [r for r in recs if r['status'] == 'ok']
    alarms = sum(1 for r in ok if r['metrics'].get('fdd.detected'))
    errors = n - len(ok)
    cells = []
    for stat, key, lower, _ in MARGINS:
        vals = [r['metrics'][stat] for r in ok if r['metrics'].get(stat) is not None]
        g = thresholds[key]
        if not vals:
            cells.append('/')
        elif lower:
            worst = min(vals)
            cells.append('%.3f (%.2fx)' % (worst, worst / g))
        else:
            worst = max(vals)
            cells.append('%.3f (%s)' % (worst, '%.2fx' % (g / worst) if worst > 0 else 'not moved'))
    return ('| %s | %s | %d | %d | %s | %d | %s |' % (name, desc, n, alarms, pct(alarms, n), errors, ' | '.join(cells)),
            (alarms, n))


def render(out_dir, present):
    thresholds = load_thresholds()
    version = subprocess.run(['git', 'describe', '--always', '--dirty'], cwd=ROOT, capture_output=True,
                             text=True).stdout.strip() or 'unknown'
    head = ['# Results', '',
            '<!-- Generated by `make results` (scripts/results.py); do not edit by hand. -->', '',
            'Every figure below is computed from the trial records of the commands named with it (a benchmark\'s',
            'table names the build that ran it), rendered at %s on %s (%d cores as the jobs saw them; the jobs ran'
            % (version, cpu_model(), os.cpu_count() or 0),
            'there, two worker threads). World: `realistic`, each trial its own vehicle',
            'drawn about the file, with the computation and ESC delays, sensors on the file\'s body frame and',
            'vibration of docs/truth.md. Rates carry their 95 % Wilson interval, means their 95 % normal',
            'interval, both in brackets. Metric definitions: docs/metrics.md.', '']
    body = []
    readme = []
    if 'ftc_rotorguard' in present:
        args = dict((j[0], j[2]) for j in JOBS)['ftc_rotorguard']
        recs = records(os.path.join(out_dir, 'ftc_rotorguard'))
        m = manifest(os.path.join(out_dir, 'ftc_rotorguard'))
        base = []
        if 'ftc_baselines' in present:
            base = records(os.path.join(out_dir, 'ftc_baselines'))
        table, single = ftc_table(recs + base, ('rotorguard', 'fixedtime', 'indi'))
        body += ['## FTC benchmark: paper 000, Tables III and IV', '',
                 '`%s` (rotorguard, %s; host %s, finished %s)' % (command_text(args), m.get('version', ''),
                                                                m.get('host', ''), m.get('finished', '')), '']
        if base:
            bargs = dict((j[0], j[2]) for j in JOBS)['ftc_baselines']
            body += ['`%s` (rotorguard, %s; FixedA = `fixedtime`, our re-implementation of the fixed-time observer with the '
                     'same NMPC; INDI driven by the same FDD)' % (command_text(bargs),
                                                                 manifest(os.path.join(out_dir, 'ftc_baselines')).get('version', '')), '']
        body += ['Single complete failures. SucR: the vehicle hovers or tracks on after the failure; MDR: the faulty',
                 'rotor not isolated correctly; FAR: a diagnosis before the onset or of another rotor; latency: onset',
                 'to isolation, over the correct isolations. The paper reports 20 trials per cell.', '', table, '']
        ff, ffd = ftc_fault_free(recs + base, ('rotorguard', 'fixedtime', 'indi'))
        body += ['Fault-free cells (every diagnosis is a false alarm; an error counts as one):', '', ff, '']
        st, sec = ftc_second(recs + base, ('rotorguard',))
        k2, n2 = false_second_in_single(recs)
        body += ['Second failures, a propeller lost 0.1-6 s after the first failure (a motor stop in hover), on the',
                 'rotor beside it (adjacent: the vehicle cannot hover on the two left and is terminated) or on its',
                 'diagonal twin (which the controller turns nearly off, so that its loss is neither needed nor',
                 'visible above the spinning vehicle\'s force-balance noise; the vehicle flies on); "adjacent, with a',
                 'parachute": the adjacent cell\'s trials with a recovery parachute fitted, released on flight',
                 'termination (docs/scenarios.md, `sim.parachute`). Impact speeds are those of the trials that crashed:',
                 '', st, '']
        adj = sec.get(('motor_stop_then_adjacent', 'rotorguard'))
        late_k = late_n = 0
        if adj:
            late = [(k, n) for (lo, hi), (k, n) in zip(BINS, adj['bins']) if lo >= 0.3]
            late_k, late_n = sum(k for k, _ in late), sum(n for _, n in late)
            body += ['Adjacent, the second failure 0.3 s or more after the first isolation: isolated in %d of %d trials (%s).'
                     % (late_k, late_n, pct(late_k, late_n)), '']
        body += ['False second isolations over the single-failure cells above: %d of %d flights (%s).' % (k2, n2, pct(k2, n2)), '']
        body += ['Propeller losses on a battery (docs/scenarios.md, `sim.battery`: a 4S pack whose voltage sags with its',
                 'load and charge, every rotor\'s largest thrust scaling with (V / V_ref)²), full and at 30 % charge, on the',
                 'trials of the cells without one:', '', ftc_battery(recs, ('rotorguard',)), '']
        body += ['Take-off failures with the rotors\' ground effect (docs/scenarios.md, `sim.ground_effect`), on the trials of',
                 'the cells without it:', '', ftc_ground_effect(recs, ('rotorguard',)), '']
        # README: the headline figures, realistic.
        def rng(keys, f):
            vals = [f(single[k]) for k in keys if k in single]
            if not vals:
                return '/'
            lo, hi = min(vals), max(vals)
            return '%.1f' % lo if abs(lo - hi) < 0.05 else '%.1f-%.1f' % (lo, hi)
        rows = []
        for phase in ('hover', 'tracking', 'takeoff'):
            keys = [(phase, f, 'rotorguard') for f in ('propeller_loss', 'motor_stop')]
            rows.append('%s %s %%' % (phase, rng(keys, lambda s: 100.0 * s['success'] / s['n'])))
        mdr = max((100.0 * s['missed'] / s['n'] for k, s in single.items() if k[2] == 'rotorguard'), default=float('nan'))
        lat = {}
        for fault in ('motor_stop', 'propeller_loss'):
            lat[fault] = ' / '.join('%.3f' % (sum(single[(p, fault, 'rotorguard')]['lat']) / len(single[(p, fault, 'rotorguard')]['lat']))
                                   for p in ('hover', 'tracking', 'takeoff') if (p, fault, 'rotorguard') in single and single[(p, fault, 'rotorguard')]['lat'])
        far_cells = ', '.join('%s %d of %d' % (ph, a, n) for (ph, meth), (a, n) in sorted(ffd.items()) if meth == 'rotorguard')
        readme += ['- FTC benchmark (paper 000, Tables III and IV), 1000 trials per cell, realistic world: SucR %s; '
                   'MDR at most %.1f %%; false alarms in the fault-free cells: %s; mean isolation latency, hover / '
                   'tracking / take-off, %s s (motor stops) and %s s (propeller losses).'
                   % ('; '.join(rows), mdr, far_cells, lat['motor_stop'], lat['propeller_loss'])]
        if adj:
            readme += ['- A second failure beside the first, 0.3 s or more after the first isolation: isolated in %s of '
                       '%d trials; false second isolations: %d in %d single-failure flights.'
                       % (pct(late_k, late_n), late_n, k2, n2)]
    if 'calibration' in present:
        with open(os.path.join(out_dir, 'calibration', 'calibration', 'calibration.json')) as f:
            cal = json.load(f)
        flights = sum(c['flights'] for c in cal['campaigns'])
        body += ['## Threshold calibration', '',
                 '`rotorguard fdd-calibrate RUNS... --healthy %s` over the calibration sets\' %d healthy flights'
                 % (' --healthy '.join(CALIBRATION_CAMPAIGNS), flights),
                 '(%s) and %d faulty runs (`rotorguard run` of `fdd_hover_motor_stop`, `fdd_hover_propeller_loss` and'
                 % ('; '.join('%d of `%s`, false alarms as flown: %d' % (c['flights'], c['campaign'], c['false_alarms'])
                              for c in cal['campaigns']), len(cal['logs'])),
                 '`fdd_takeoff_propeller_loss`, both kinds, each rotor, seeds 111-144, realistic). The suggestion is the',
                 'fastest value with no false alarm, the fewest misses and a margin of %gx to the most alarming healthy value;'
                 % cal['margin_required'],
                 'docs/fdd.md says why a shipped value differs from it.', '',
                 '| threshold | shipped | its margin | detected / missed of %d | mean latency (s) | suggested | its margin | mean latency (s) |'
                 % len(cal['logs']),
                 '|---|---|---|---|---|---|---|---|']
        for sw in cal['sweeps']:
            shipped = thresholds.get(sw['threshold'])
            row = min(sw['rows'], key=lambda r: abs(r['value'] - shipped)) if shipped is not None and sw['rows'] else None
            sug = sw.get('suggested')
            fmt = lambda v, d=3: '/' if v is None else '%.*f' % (d, v)
            body.append('| %s | %g | %s | %s | %s | %s | %s | %s |' % (
                sw['threshold'], shipped,
                ('unbounded (the rule never moved)' if row['margin'] is None else fmt(row['margin'], 2) + 'x')
                if row and abs(row['value'] - shipped) < 1e-9 else '/',
                '%d / %d' % (row['detected'], row['missed']) if row else '/',
                fmt(row['latency_s_mean']) if row else '/',
                '%g' % sug['value'] if sug else 'none', fmt(sug['margin'], 2) + 'x' if sug else '/',
                fmt(sug['latency_s_mean']) if sug else '/'))
        cal_seeds = set(int(x) for c in cal['campaigns'] for x in c['trial_seeds'])
        shared = []
        for name, kind, _, _ in JOBS:
            if kind == 'campaign' and name in present:
                seeds = set(int(r['params']['seed']) for r in records(os.path.join(out_dir, name)))
                shared.append('%s %d' % (name.replace('far_', ''), len(seeds & cal_seeds)))
        if shared:
            body += ['', 'Vehicles the evaluation sets below share with the calibration\'s %d: %s.'
                     % (len(cal_seeds), ', '.join(shared))]
        body.append('')
    for world in ('realistic', 'ideal'):
        name = 'mars_' + world
        if name not in present:
            continue
        args = dict((j[0], j[2]) for j in JOBS)[name]
        with open(os.path.join(out_dir, name, 'bench.md')) as f:
            table = f.read().strip()
        # The bench's own headings one level below this page's.
        table = re.sub(r'^(#+) ', lambda m: '#' + m.group(1) + ' ', table, flags=re.M)
        m = manifest(os.path.join(out_dir, name))
        body += ['## Modular assemblies (paper 002), %s world' % world, '',
                 '`%s` (rotorguard, %s; host %s, finished %s)' % (command_text(args), m.get('version', ''),
                                                                m.get('host', ''), m.get('finished', '')), '', table, '']
        if world == 'realistic':  # README: Table II's success of ours, row by row
            with open(os.path.join(out_dir, name, 'bench.json')) as f:
                bench = json.load(f)
            cells = []
            for r in bench.get('table2') or []:
                if 'ours_success_rate' not in r:
                    continue
                cell = '%s %s %.0f %%' % (r['shape'].replace('mars_', ''), r['fault'], 100.0 * r['ours_success_rate'])
                capable = r.get('ours_success_rate_hover_capable')
                if r.get('hover_capable_trials', bench['trials']) < bench['trials'] and capable is not None:
                    cell += ' (%.0f %% where it can hover: %d of %d drawn assemblies cannot)' % (
                        100.0 * capable, bench['trials'] - r['hover_capable_trials'], bench['trials'])
                cells.append(cell)
            if cells:
                readme += ['- Modular assemblies (paper 002, Table II), %d trials per row, realistic world: ours succeeds '
                           'in %s.' % (bench['trials'], '; '.join(cells))]
    far = [j for j in JOBS if j[1] == 'campaign' and j[0] in present]
    if far:
        body += ['## False alarms on evaluation sets', '',
                 'Healthy flights, composite FDD armed throughout (landings included: the detector is not switched',
                 'off on the ground, it understands it). Each set derives its vehicles from its own seed stream; no',
                 'threshold was calibrated on any of them (the calibration sets are `fdd_calibration_*`). A',
                 'margin is the most alarming healthy value of a rule\'s statistic against its threshold (docs/metrics.md):',
                 'the lowest debounced motor index over gamma_M = %g, gamma_P = %g over the highest persistent propeller'
                 % (thresholds['motor_index_threshold'], thresholds['propeller_index_threshold']),
                 'index, the take-off threshold %g over the highest gated take-off index, gamma_S = %g over the highest'
                 % (thresholds['takeoff_index_threshold'], thresholds['motor_shortfall_threshold']),
                 'debounced motor shortfall (`/`: a set flown before that rule).', '',
                 '| set | flights | n | false alarms | FAR | errors | lowest debounced M_i (margin) | highest persistent P_i (margin) | highest gated take-off index (margin) | highest debounced S_i (margin) |',
                 '|---|---|---|---|---|---|---|---|---|---|']
        total = [0, 0]
        where = []
        for name, _, args, desc in far:
            recs = records(os.path.join(out_dir, name))
            row, (a, n) = far_row('`%s`' % args[2].split('/')[-1].replace('.yaml', ''), desc, recs, thresholds)
            body.append(row)
            total[0] += a
            total[1] += n
            if a:
                where.append('%d in %s' % (a, name.replace('far_', '').replace('_', ' ')))
        builds = {}
        for name, _, _, _ in far:
            builds.setdefault(manifest(os.path.join(out_dir, name)).get('version', 'unknown'), []).append(name.replace('far_', ''))
        body += ['', 'Each set: `rotorguard campaign run configs/campaigns/<set>.yaml --out DIR`, then `campaign merge DIR`; '
                 'flown by rotorguard %s.' % '; '.join('%s (%s)' % (v, ', '.join(sets)) for v, sets in sorted(builds.items())),
                 'All sets together: %d false alarm%s in %d flights (%s).' % (total[0], '' if total[0] == 1 else 's', total[1],
                                                                             pct(total[0], total[1])), '']
        readme += ['- False alarms on %d healthy evaluation flights (%s, 1000 each): %d (%s)%s.'
                   % (total[1], ', '.join(j[0].replace('far_', '').replace('_', ' ') for j in far), total[0],
                      pct(total[0], total[1]), ': ' + ', '.join(where) if where else '')]
    if 'nmpc_tracking' in present:
        version, rows = load_flights(os.path.join(out_dir, 'nmpc_tracking'))
        med = lambda key: median([r[key] for r in rows])
        body += ['## Post-failure tracking: the 1 m/s lemniscate with propeller 0 lost', '',
                 '`rotorguard run %s --seed K` for K = 1..%d, as shipped: drawn delays (the stack expects 3 ms),'
                 % (TRACKING_SCENARIO, len(rows)),
                 'wind gusts of 0.3 m/s, the tracking window from 5 s. The estimate\'s error against the reference is',
                 'what the controller achieves; the truth\'s against the reference adds the odometry\'s drift (the',
                 'estimate\'s error against the truth). Paper 000\'s real flights: 0.14-0.15 m.' + built(version), '',
                 '| flights | successes | estimate vs reference, median (m) | truth vs reference, median (m) | estimate vs truth, median (m) |',
                 '|---|---|---|---|---|',
                 '| %d | %d | %.3f | %.3f | %.3f |' % (len(rows), sum(1 for r in rows if r['success']), med('est_vs_ref'),
                                                    med('truth_vs_ref'), med('est_vs_truth')), '']
        readme += ['- Post-failure tracking (1 m/s lemniscate, propeller 0 lost, %d seeds): median error of the estimate '
                   'against the reference %.3f m; of the truth %.3f m, of which the odometry drift (estimate against '
                   'truth) %.3f m.' % (len(rows), med('est_vs_ref'), med('truth_vs_ref'), med('est_vs_truth'))]
    if 'nmpc_delay' in present:
        version, rows = load_flights(os.path.join(out_dir, 'nmpc_delay'))
        body += ['## The NMPC\'s assumed delay against the true one', '',
                 'The same flights with the true delay fixed at 3.5 ms (2.5 ms of computation, 1 ms of ESC latency,',
                 'the computation within 25 % jitter) while the NMPC predicts over `stack.command_delay_s` = D:', '',
                 '| D (ms) | of the true delay | flights | successes | estimate vs reference, median (m) | truth vs reference, median (m) |',
                 '|---|---|---|---|---|---|']
        for d in ASSUMED_DELAYS:
            rs = [r for r in rows if r['sets'][-1] == 'stack.command_delay_s=%g' % d]
            body.append('| %g | %s | %d | %d | %.3f | %.3f |' % (
                d * 1000, {0.0: 'none', 0.00175: 'half', 0.0035: 'equal', 0.007: 'double'}[d], len(rs),
                sum(1 for r in rs if r['success']), median([r['est_vs_ref'] for r in rs]),
                median([r['truth_vs_ref'] for r in rs])))
        body += ['', 'Each flight: `rotorguard run %s --seed K --set truth.computation_delay_min_s=0.0025 --set '
                 'truth.computation_delay_max_s=0.0025 --set truth.esc_command_latency_min_s=0.001 --set '
                 'truth.esc_command_latency_max_s=0.001 --set stack.command_delay_s=D`%s.' % (TRACKING_SCENARIO, built(version)), '']
    if 'shipped' in present:
        version, rows = load_flights(os.path.join(out_dir, 'shipped'))
        body += ['## Every shipped scenario at 50 seeds', '',
                 '`rotorguard run configs/scenarios/NAME.yaml --seed K --set truth=WORLD` for K = %d..%d (vehicles no test'
                 % (SHIPPED_SEEDS[0], SHIPPED_SEEDS[-1]),
                 'or document flies: ctest flies seeds 1-3), in the realistic world and, beside it, the ideal one. A file',
                 'that states `truth: ideal` is not yet realistic (the file says why). A scenario written to show a',
                 'failure succeeds when it shows that failure (the words in brackets)%s.' % built(version), '',
                 '| scenario | states | world | flights | successes | rate | failures (most frequent reasons) |',
                 '|---|---|---|---|---|---|---|']
        stated = dict((n, w) for n, _, w in shipped_scenarios())
        realistic_k = realistic_n = 0
        weakest = []
        for name, _, _ in shipped_scenarios():
            for world in ('realistic', 'ideal'):
                rs = [r for r in rows if r['label'].startswith('%s_%s_seed' % (name, world))]
                if not rs:
                    continue
                intended = INTENDED_FAILURES.get(name)
                ok = [(intended in (r['failure_reason'] or '')) if intended else r['success'] for r in rs]
                k, n = sum(ok), len(rs)
                reasons = {}
                for r, good in zip(rs, ok):
                    if not good:  # the reason's kind: its words up to the first figure
                        why = re.split(r'[0-9]', r['failure_reason'] or 'succeeded')[0].rstrip(' :=(,')
                        reasons[why] = reasons.get(why, 0) + 1
                top = '; '.join('%s (%d)' % (w, c) for w, c in sorted(reasons.items(), key=lambda x: -x[1])[:2])
                body.append('| `%s`%s | %s | %s | %d | %d | %s | %s |' % (
                    name, ' (%s)' % intended if intended else '', stated[name], world, n, k, pct(k, n), top or '/'))
                if world == 'realistic' and stated[name] == 'realistic':
                    realistic_k += k
                    realistic_n += n
                    weakest.append((k / n if n else 0.0, name, k, n))
        body += ['', 'Over the scenarios that state `realistic`: %d of %d flights as intended (%s).'
                 % (realistic_k, realistic_n, pct(realistic_k, realistic_n)), '']
        weakest.sort()
        readme += ['- Every shipped scenario that states the realistic world, at 50 fresh seeds each: %d of %d flights '
                   'as intended (%s); the weakest, `%s`, %d of %d.'
                   % (realistic_k, realistic_n, pct(realistic_k, realistic_n), weakest[0][1], weakest[0][2],
                      weakest[0][3])]
    missing = [j[0] for j in JOBS if j[0] not in present]
    if missing:
        body += ['## Not in this page', '', 'Jobs of `make results` not run for this page: %s.' % ', '.join(missing), '']
    with open(os.path.join(ROOT, 'docs/results.md'), 'w') as f:
        f.write('\n'.join(head + body).rstrip() + '\n')
    write_readme_block(readme)


def span(values, fmt='%.0f'):
    """'a' when every run gave the same figure, else 'min-max'."""
    lo, hi = fmt % min(values), fmt % max(values)
    return lo if lo == hi else '%s-%s' % (lo, hi)


def performance_page(out_dir):
    """docs/performance.md's text from the performance job's records (None when it has none)."""
    folder = os.path.join(out_dir, 'performance')
    if not finished('peers', folder):
        return None
    with open(os.path.join(folder, 'manifest.json')) as f:
        m = json.load(f)
    runs = {}
    for name, _, repeats in PEER_DRIVERS:
        runs[name] = []
        for k in range(1, repeats + 1):
            with open(os.path.join(folder, '%s.%d.json' % (name, k))) as f:
                runs[name].append(json.load(f))
    peers = m['peers']
    revisions = sorted({r['host']['git_revision'] for rs in runs.values() for r in rs})
    if len(revisions) != 1:
        sys.exit('results: performance: its runs come from several builds (%s): delete %s and run the job again'
                 % (', '.join(revisions), folder))
    out = ['# Performance beside the peers', '',
           '<!-- Generated by `make results` (scripts/results.py, job `performance`); do not edit by hand. -->', '',
           'rotorguard\'s solvers measured beside open peers of the field on the same problems, in one process, on one',
           'core, the sides taking turns problem by problem so that neither always runs first. Machine: %s, %d cores'
           % (m['cpu'], m['cores']),
           '(a VM: its times move by up to a third from run to run, so the QP and L-BFGS drivers ran 3 times, taking turns,',
           'and every run is given: ranges are over the runs, ratios are taken within each run). Finished %s with'
           % m['finished'],
           'rotorguard %s (%s), built by `%s` %s (`%s`, Release).' % (
               runs['peer_qp'][0]['host']['version'], revisions[0], os.path.basename(m['compiler']) or 'c++',
               runs['peer_qp'][0]['host']['compiler'],
               m['rotorguard_flags']), '',
           '## How to run it', '',
           'The peers are never part of this repository. `make peers` installs git and TBB (`scripts/install-deps.sh',
           '--peers`) and runs `scripts/peers.sh out/peers`, which clones each peer at the commit below into',
           '`out/peers/src` and builds it there, then configures this build with `ROTORGUARD_PEERS_DIR=out/peers`, which',
           'adds the three drivers of `benchmarks/peers/` (rotorguard\'s code, calling the peers\' public APIs). Then:', '',
           '```',
           'make peers',
           'rm -rf out/results/performance   # else the packed records count as the finished job',
           'python3 scripts/results.py --only performance --qp-instance qp_hover_n20_v2.json',
           '```', '',
           '| peer | commit | built with |', '|---|---|---|',
           '| BLASFEO | `%s` | `TARGET=%s`, `LA=HIGH_PERFORMANCE` |' % (peers['giaf/blasfeo'][:12], peers['blasfeo_target']),
           '| HPIPM | `%s` | `TARGET=%s` |' % (peers['giaf/hpipm'][:12], peers['hpipm_target']),
           '| GCOPTER (`gcopter/include/gcopter/lbfgs.hpp`, header only) | `%s` | with rotorguard\'s flags |'
           % peers['ZJU-FAST-Lab/GCOPTER'][:12],
           '| KISS-ICP (`cpp/kiss_icp`: core and pipeline) | `%s` | its own CMake (Release), `%s`, Debian\'s TBB |'
           % (peers['PRBonn/kiss-icp'][:12], peers.get('kiss_icp_flags') or 'no ISA flag'),
           '| Sophus, robin-map (KISS-ICP\'s) | `%s`, `%s` | the versions KISS-ICP\'s build fetches (1.24.6, 1.4.0) |'
           % (peers['strasdat/Sophus'][:12], peers['Tessil/robin-map'][:12]), '']
    qp = runs['peer_qp']
    names = [sd['name'] for sd in qp[0]['sides']]
    side = lambda r, n: next(sd for sd in r['sides'] if sd['name'] == n)
    cases = side(qp[0], 'rotorguard')
    out += ['## The NMPC\'s QP beside HPIPM', '',
            '`%s`, the reference OCP QP of the NMPC\'s size (N = 20, 17 states, 4 inputs; input bounds at stages'
            % m['commands']['peer_qp'],
            '0..N-1, three rate bounds at 1..N; %d cases with about 20 active bounds, "stress", %d with about one, "track"),'
            % (cases['cases_stress'], cases['cases_track']),
            'each solved cold, a case\'s time the fastest of 3 solves, each solve taking the problem\'s data as an NMPC',
            'step hands them over. HPIPM is given the problem as its users give it, x0 eliminated, and its settings are',
            'frozen in the driver (`benchmarks/peers/peer_qp.cc`). An answer is wrong when its u0 is more than 1e-4 from',
            'the instance\'s certified optimum; "not converged": HPIPM\'s own status (those answers may still be right).',
            'Iterations: active-set changes for rotorguard, interior-point iterations for HPIPM.', '',
            '| solver | settings | stress median / p99 [us] | track median / p99 [us] | wrong u0 | not converged | '
            'largest u0 error | iterations |', '|---|---|---|---|---|---|---|---|']
    for n in names:
        rows = [side(r, n) for r in qp]
        out.append('| %s | %s | %s / %s | %s / %s | %s of %d | %s | %s | %s |' % (
            '**rotorguard**' if n == 'rotorguard' else n.replace('_', ' '), rows[0]['settings'],
            span([x['stress_us_median'] for x in rows]), span([x['stress_us_p99'] for x in rows]),
            span([x['track_us_median'] for x in rows]), span([x['track_us_p99'] for x in rows]),
            span([x['cases_u0_error_above_1e-4'] for x in rows]), rows[0]['cases_stress'] + rows[0]['cases_track'],
            span([x['not_converged'] for x in rows]), span([x['max_u0_error'] for x in rows], '%.1e'), span([x['iterations_mean'] for x in rows], '%.1f')))
    fast = [n for n in names if n.startswith('hpipm_fast')]
    out += ['', 'rotorguard\'s time over HPIPM\'s, per run (below 1: rotorguard faster); "best fast" is, per figure, the',
            'faster of HPIPM\'s two fast modes in that run; ROBUST is the mode that answered every case right:', '',
            '| figure | over the best fast mode | over ROBUST |', '|---|---|---|']
    for key, label in (('stress_us_median', 'stress median'), ('stress_us_p99', 'stress p99'),
                       ('track_us_median', 'track median'), ('track_us_p99', 'track p99')):
        best = [side(r, 'rotorguard')[key] / min(side(r, n)[key] for n in fast) for r in qp]
        acc = [side(r, 'rotorguard')[key] / side(r, 'hpipm_robust')[key] for r in qp]
        out.append('| %s | %s | %s |' % (label, span(best, '%.2f'), span(acc, '%.2f')))
    lb = runs['peer_lbfgs']
    out += ['', '## The planner\'s L-BFGS beside GCOPTER\'s', '',
            '`%s`: the planner\'s objective (`TrajectoryOptimizer::Objective`) on the free-space problems MINCO'
            % m['commands']['peer_lbfgs'],
            'optimisers are compared on (docs/planning.md, "The optimiser in free space": 200 problems of 5 and of 10',
            'pieces, seed 1), minimised from the same start by the planner\'s own L-BFGS and by GCOPTER\'s',
            '`lbfgs::lbfgs_optimize` with the parameters GCOPTER\'s planner sets (256 pairs, past 3, g_epsilon 0,',
            'min_step 1e-32; its relative cost tolerance `delta` set to rotorguard\'s 1e-4, where GCOPTER\'s example',
            'configuration has 1e-5). Two budgets: the planner\'s 200 iterations for both, and none (GCOPTER\'s planner',
            'sets none), where each stops by its own decrease test. Time: the optimisation alone, the fastest of 3 per problem, the median over the',
            'problems. The difference is per problem, rotorguard\'s final cost minus GCOPTER\'s (below 0:',
            'rotorguard ends lower), with its standard error.', '',
            '| pieces | budget | rotorguard [us] | GCOPTER [us] | ratio | mean cost, rotorguard / GCOPTER | '
            'difference | rotorguard lower in | evaluations, rotorguard / GCOPTER |',
            '|---|---|---|---|---|---|---|---|---|']
    for i, size in enumerate(lb[0]['sizes']):
        rows = [r['sizes'][i] for r in lb]
        for budget, label in (('200', '200 iterations'), ('unlimited', 'none')):
            own, peer = 'rotorguard_' + budget, 'gcopter_' + budget
            out.append('| %d | %s | %s | %s | %s | %s / %s | %+.2f ± %.2f | %d of %d | %.0f / %.0f |' % (
                size['pieces'], label, span([x[own + '_us_median'] for x in rows]),
                span([x[peer + '_us_median'] for x in rows]),
                span([x[own + '_us_median'] / x[peer + '_us_median'] for x in rows], '%.2f'),
                '%.2f' % size[own + '_cost_mean'], '%.2f' % size[peer + '_cost_mean'],
                size['cost_difference_%s_mean' % budget], size['cost_difference_%s_stderr' % budget],
                size['problems_rotorguard_lower_' + budget], size['problems'],
                size[own + '_evaluations_mean'], size[peer + '_evaluations_mean']))
    same = all(r['sizes'][i][k] == lb[0]['sizes'][i][k] for r in lb for i in range(len(lb[0]['sizes']))
               for k in lb[0]['sizes'][i] if k.endswith('_cost_mean'))
    out += ['', 'The costs are the same in every run (both optimisers are deterministic); only the times move.' if same
            else 'The costs differ between the runs: those given are the first run\'s.', '']
    lio = runs['peer_lio'][0]
    kc = lio['kiss_icp']
    out += ['## The odometry beside KISS-ICP', '',
            '`%s`: the frames of `rotorguard bench lio` (the simulated MID-360 and the vibrating IMU; a 500-tree'
            % m['commands']['peer_lio'],
            'forest and a room with a ceiling; hovering and flying 1 m/s; spinning at 0-20 rad/s; %.0f s a condition),'
            % lio['duration_s'],
            'each given to rotorguard\'s LiDAR-inertial odometry (with the IMU) and then to a KISS-ICP of its own',
            '(LiDAR only: the points in the sensor frame with their times, which it deskews by its constant-velocity',
            'model; so the error ratio also measures what the IMU is worth, and no LiDAR-inertial peer is run here). KISS-ICP is configured as its defaults with this LiDAR\'s range: max_range %.0f m, voxel_size %.1f m'
            % (kc['max_range'], kc['voxel_size']),
            '(max_range / 100, its rule), min_range %.0f, deskew on, %d thread; built with rotorguard\'s ISA flag. Both start'
            % (kc['min_range'], kc['max_num_threads']),
            'at the true pose (KISS-ICP\'s at its first frame\'s last point, where its first pose is). Error: the',
            'position after each frame against the truth (rotorguard\'s body, KISS-ICP\'s sensor), RMSE / largest over',
            'the frames; diverged: an error past 1 m. Time: each frame\'s `Lio::OnFrame` and `KissICP::RegisterFrame`, medians.', '',
            '| scene | motion | spin [rad/s] | rotorguard error [m] | KISS-ICP error [m] | error ratio | rotorguard [ms] '
            '| KISS-ICP [ms] | time ratio |', '|---|---|---|---|---|---|---|---|---|']
    for r in lio['runs']:
        out.append('| %s | %s | %.0f | %.3f / %.3f%s | %.3f / %.3f%s | %.1f | %.2f | %.1f | %.1f |' % (
            r['scene'], r['motion'], r['spin_rad_s'], r['rotorguard_error_rmse_m'], r['rotorguard_error_max_m'],
            ' (diverged)' if r['rotorguard_diverged'] else '', r['kiss_icp_error_rmse_m'], r['kiss_icp_error_max_m'],
            ' (diverged)' if r['kiss_icp_diverged'] else '', r['kiss_icp_error_rmse_m'] / max(r['rotorguard_error_rmse_m'], 1e-9),
            r['rotorguard_frame_ms_median'], r['kiss_icp_frame_ms_median'],
            r['kiss_icp_frame_ms_median'] / max(r['rotorguard_frame_ms_median'], 1e-9)))
    ratios = [r['kiss_icp_error_rmse_m'] / max(r['rotorguard_error_rmse_m'], 1e-9) for r in lio['runs']]
    times = [r['kiss_icp_frame_ms_median'] / max(r['rotorguard_frame_ms_median'], 1e-9) for r in lio['runs']]
    out += ['', 'KISS-ICP\'s error over rotorguard\'s: %.1f-%.1f (median %.1f); its time a frame over rotorguard\'s: '
            '%.1f-%.1f (median %.1f). KISS-ICP diverges in %d of %d conditions, rotorguard in %d. One run (seed 1); a'
            % (min(ratios), max(ratios), median(ratios), min(times), max(times), median(times),
               sum(r['kiss_icp_diverged'] for r in lio['runs']), len(lio['runs']),
               sum(r['rotorguard_diverged'] for r in lio['runs'])),
            'time is the median of a condition\'s frames.', '']
    return '\n'.join(out)


def check_performance(records_path):
    """Exit 1 when docs/performance.md differs from the page the packed records render."""
    import tempfile
    with tempfile.TemporaryDirectory() as tmp:
        unpack(records_path, tmp)
        page = performance_page(tmp)
    if page is None:
        sys.exit('results: %s holds no performance job' % records_path)
    with open(os.path.join(ROOT, 'docs', 'performance.md')) as f:
        if f.read() != page:
            print('results: docs/performance.md is not the page %s renders (run scripts/results.py --render-only)'
                  % records_path)
            sys.exit(1)
    print('results: docs/performance.md is the page the packed records render')


def write_readme_block(lines):
    path = os.path.join(ROOT, 'README.md')
    with open(path) as f:
        text = f.read()
    begin, end = '<!-- BEGIN results -->\n', '<!-- END results -->'
    i, j = text.find(begin), text.find(end)
    if i < 0 or j < 0:
        sys.exit('results: README.md has no <!-- BEGIN results --> ... <!-- END results --> block')
    text = text[:i + len(begin)] + '\n'.join(lines) + '\n' + text[j:]
    with open(path, 'w') as f:
        f.write(text)


def pack(out_dir, path):
    """Writes out_dir's job folders into path, a tar.xz that is the same for the same records: names
    sorted, times and owners cleared; the flights' logs (kept only for fdd-calibrate) and lock files
    left out, and an unfinished calibration left out whole (its runs must be flown again for their logs)."""
    import io
    import tarfile
    names = set(j[0] for j in JOBS)
    members = []
    for dirpath, dirnames, filenames in os.walk(out_dir):
        dirnames.sort()
        rel = os.path.relpath(dirpath, out_dir)
        top = rel.split(os.sep)[0]
        if rel == '.' or top not in names:
            continue
        if top == 'calibration' and not finished('calibration', os.path.join(out_dir, 'calibration')):
            continue
        for f in sorted(filenames):
            if f.endswith('.lock') or (rel.split(os.sep)[:2] == ['calibration', 'runs'] and f != 'summary.json'):
                continue
            members.append(os.path.join(rel, f))
    os.makedirs(os.path.dirname(path), exist_ok=True)
    partial = path + '.partial'
    with tarfile.open(partial, 'w:xz', preset=9) as tar:
        for rel in sorted(members):
            with open(os.path.join(out_dir, rel), 'rb') as f:
                data = f.read()
            info = tarfile.TarInfo(rel.replace(os.sep, '/'))
            info.size, info.mtime, info.mode = len(data), 0, 0o644
            tar.addfile(info, io.BytesIO(data))
    os.replace(partial, path)
    print('results: %d files of %s packed into %s (%.1f MB)' % (len(members), out_dir, path,
                                                              os.path.getsize(path) / 1e6), flush=True)


def unpack(path, out_dir):
    """Starts out_dir from the packed records when it holds no job yet."""
    import tarfile
    if not os.path.exists(path) or any(os.path.isdir(os.path.join(out_dir, j[0])) for j in JOBS):
        return
    with tarfile.open(path, 'r:xz') as tar:
        for m in tar.getmembers():
            if not m.isfile() or m.name.startswith('/') or '..' in m.name.split('/'):
                sys.exit('results: %s: member %r is not a record file' % (path, m.name))
        tar.extractall(out_dir)
    print('results: %s started from %s' % (out_dir, path), flush=True)


def self_test():
    """pack and unpack on made-up records: the same records pack to the same bytes, unpack to the
    same files, the flights' logs, lock files and an unfinished calibration left out."""
    import tempfile
    with tempfile.TemporaryDirectory() as tmp:
        out = os.path.join(tmp, 'out')
        files = {'ftc_rotorguard/results.jsonl': '{"trial":0}\n', 'ftc_rotorguard/manifest.json': '{}',
                 'ftc_rotorguard/manifest.json.lock': '', 'shipped/hover_realistic_seed1001/summary.json': '{}',
                 'calibration/fdd_calibration_takeoff/results.jsonl': '{"trial":0}\n',
                 'calibration/runs/hover_motor_0/summary.json': '{}',
                 'calibration/runs/hover_motor_0/sensors.csv': 't\n', 'unrelated/file.txt': 'x'}
        for rel, text in files.items():
            os.makedirs(os.path.dirname(os.path.join(out, rel)), exist_ok=True)
            with open(os.path.join(out, rel), 'w') as f:
                f.write(text)
        first, second = os.path.join(tmp, 'a.tar.xz'), os.path.join(tmp, 'b.tar.xz')
        pack(out, first)
        os.utime(os.path.join(out, 'ftc_rotorguard/results.jsonl'), (1, 1))  # times do not count
        pack(out, second)
        with open(first, 'rb') as f, open(second, 'rb') as g:
            assert f.read() == g.read(), 'the same records packed to different bytes'
        back = os.path.join(tmp, 'back')
        unpack(first, back)
        got = sorted(os.path.relpath(os.path.join(d, f), back) for d, _, fs in os.walk(back) for f in fs)
        assert got == ['ftc_rotorguard/manifest.json', 'ftc_rotorguard/results.jsonl',
                       'shipped/hover_realistic_seed1001/summary.json'], got
        with open(os.path.join(back, 'ftc_rotorguard/results.jsonl')) as f:
            assert f.read() == '{"trial":0}\n'
        # A finished calibration keeps its campaigns and the runs' summaries, never their logs.
        os.makedirs(os.path.join(out, 'calibration/calibration'))
        with open(os.path.join(out, 'calibration/calibration/calibration.json'), 'w') as f:
            f.write('{}')
        pack(out, first)
        again = os.path.join(tmp, 'again')
        unpack(first, again)
        assert os.path.exists(os.path.join(again, 'calibration/runs/hover_motor_0/summary.json'))
        assert not os.path.exists(os.path.join(again, 'calibration/runs/hover_motor_0/sensors.csv'))
        # A folder that already holds a job is not overwritten.
        with open(os.path.join(again, 'ftc_rotorguard/results.jsonl'), 'w') as f:
            f.write('newer')
        unpack(second, again)
        with open(os.path.join(again, 'ftc_rotorguard/results.jsonl')) as f:
            assert f.read() == 'newer'
    print('results: self-test passed')


def main():
    global SOURCE
    if sys.argv[1:] == ['--self-test']:
        self_test()
        return
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument('--build', default=os.path.join(ROOT, 'build'))
    ap.add_argument('--source', default=ROOT, help='the checkout the build was built from, whose configs the jobs fly')
    ap.add_argument('--out', default=os.path.join(ROOT, 'out', 'results'))
    ap.add_argument('--only', nargs='*', default=None, help='run only these jobs (the page shows every finished one)')
    ap.add_argument('--render-only', action='store_true', help='run nothing; render the finished jobs')
    ap.add_argument('--records', default=RECORDS, help='the packed records a run starts from and --pack writes')
    ap.add_argument('--pack', action='store_true', help='after the jobs, pack OUT into RECORDS')
    ap.add_argument('--pack-only', action='store_true', help='run and render nothing; pack OUT into RECORDS')
    ap.add_argument('--qp-instance', default=None, help='the NMPC\'s reference QP instance the performance job '
                    'solves (qp_hover_n20_v2.json; not in the repository)')
    ap.add_argument('--check-performance', action='store_true', help='run nothing; exit 1 when docs/performance.md '
                    'is not the page the packed records render')
    a = ap.parse_args()
    SOURCE = os.path.abspath(a.source)
    if not os.path.isdir(os.path.join(SOURCE, 'configs')):
        sys.exit('results: --source %s: not a rotorguard checkout (no configs/)' % a.source)
    RUN_JOBS['shipped'] = shipped_flights()
    binary = os.path.join(a.build, 'bin', 'rotorguard')
    if a.pack_only:
        pack(a.out, a.records)
        return
    if a.check_performance:
        check_performance(a.records)
        return
    if not a.render_only and not os.access(binary, os.X_OK):
        sys.exit('results: %s: no rotorguard binary (build it first: make build)' % binary)
    os.makedirs(a.out, exist_ok=True)
    unpack(a.records, a.out)
    for name, kind, args, _ in JOBS:
        folder = os.path.join(a.out, name)
        if a.render_only or (a.only is not None and name not in a.only) or finished(kind, folder):
            continue
        if kind == 'calibration':
            print('results: calibration: %s, %d faulty runs, fdd-calibrate' % (', '.join(CALIBRATION_CAMPAIGNS),
                                                                            len(CALIBRATION_RUNS)), flush=True)
            run_calibration(binary, folder)
        elif kind == 'peers':
            run_peers(a.build, folder, a.qp_instance)
        elif kind == 'runs':
            print('results: %s: %d flights of rotorguard run' % (name, len(RUN_JOBS[name])), flush=True)
            run_flights(binary, name, folder)
        else:
            run_job(binary, name, kind, args, folder)
    present = {name for name, kind, _, _ in JOBS if finished(kind, os.path.join(a.out, name))}
    render(a.out, present)
    page = performance_page(a.out)
    if page is not None:
        with open(os.path.join(ROOT, 'docs', 'performance.md'), 'w') as f:
            f.write(page)
    print('results: docs/results.md and README.md written from %s' % ', '.join(sorted(present)) if present
          else 'results: nothing finished yet')
    if a.pack:
        pack(a.out, a.records)


if __name__ == '__main__':
    main()
