"""Sweeps the onset of a propeller loss and plots the success rate with 95 % Wilson intervals.

Each onset is flown over several seeds (each seed draws its own vehicle about the file, its noise
and wind: docs/truth.md); the flights run in threads, which rotorguard.run lets run in parallel.

    PYTHONPATH=build/python /usr/bin/python3 examples/python/onset_sweep.py --seeds 20 --png out/python/onset_sweep.png
"""
import argparse
import concurrent.futures
import os
import sys

import matplotlib

matplotlib.use("Agg")  # files only: no display needed
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

import rotorguard  # noqa: E402

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scenario", default=os.path.join(ROOT, "configs/scenarios/fdd_takeoff_propeller_loss.yaml"))
    parser.add_argument("--key", default="faults.0.onset.during_takeoff_s", help="the onset's key in the scenario")
    parser.add_argument("--onsets", type=float, nargs="+", default=[0.05, 0.1, 0.2, 0.4, 0.8, 1.6])
    parser.add_argument("--seeds", type=int, default=10, help="flights per onset (seeds 1..N)")
    parser.add_argument("--truth", default="realistic", help="ideal or realistic (docs/truth.md)")
    parser.add_argument("--duration", type=float, help="seconds to fly (default: the scenario's)")
    parser.add_argument("--threads", type=int, default=os.cpu_count() or 1)
    parser.add_argument("--png", default="out/python/onset_sweep.png")
    args = parser.parse_args()

    def fly(onset, seed):
        overrides = {args.key: onset, "truth": args.truth}
        if args.duration:
            overrides["duration_s"] = args.duration
        return rotorguard.run(args.scenario, set=overrides, seed=seed, log=False).success

    with concurrent.futures.ThreadPoolExecutor(max_workers=args.threads) as pool:
        flights = {(onset, seed): pool.submit(fly, onset, seed)
                   for onset in args.onsets for seed in range(1, args.seeds + 1)}
        successes = [sum(flights[(onset, seed)].result() for seed in range(1, args.seeds + 1))
                     for onset in args.onsets]

    rate = np.array(successes) / args.seeds
    intervals = np.array([rotorguard.wilson_interval(s, args.seeds) for s in successes])
    print(f"{'onset':>8}  success  95 % Wilson")
    for onset, s, (lo, hi) in zip(args.onsets, successes, intervals):
        print(f"{onset:8.3f}  {s:3d}/{args.seeds:<3d}  [{lo:.2f}, {hi:.2f}]")

    figure, ax = plt.subplots(figsize=(7, 4), constrained_layout=True)
    ax.errorbar(args.onsets, rate, yerr=[rate - intervals[:, 0], intervals[:, 1] - rate], fmt="o-", capsize=4)
    ax.set_xscale("log")
    ax.set_ylim(-0.05, 1.05)
    ax.set_xlabel(f"{args.key} [s]")
    ax.set_ylabel("success rate")
    ax.set_title(f"{os.path.basename(args.scenario)}, truth {args.truth}, {args.seeds} seeds per onset")
    ax.grid(alpha=0.3)
    os.makedirs(os.path.dirname(os.path.abspath(args.png)), exist_ok=True)
    figure.savefig(args.png, dpi=110)
    print(f"wrote {args.png}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
