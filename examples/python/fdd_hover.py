"""Flies the FDD hover scenario (a propeller lost on rotor 0 at t = 2 s) and plots each rotor's
thrust and the composite FDD's indices (motor index M_i, propeller index P_i; docs/fdd.md) to a PNG.

    PYTHONPATH=build/python /usr/bin/python3 examples/python/fdd_hover.py --png out/python/fdd_hover.png
"""
import argparse
import os
import sys

import matplotlib

matplotlib.use("Agg")  # files only: no display needed
import matplotlib.pyplot as plt  # noqa: E402

import rotorguard  # noqa: E402

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scenario", default=os.path.join(ROOT, "configs/scenarios/fdd_hover_propeller_loss.yaml"))
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--duration", type=float, help="seconds to fly (default: the scenario's)")
    parser.add_argument("--png", default="out/python/fdd_hover.png")
    args = parser.parse_args()

    overrides = {"duration_s": args.duration} if args.duration else None
    result = rotorguard.run(args.scenario, set=overrides, seed=args.seed)
    log, summary = result.log, result.summary
    rotors = sum(1 for name in log if name.startswith("thrust_"))
    if "mi_0" not in log:
        sys.exit(f"{args.scenario} flies without the composite FDD: no indices to plot")

    figure, axes = plt.subplots(3, 1, sharex=True, figsize=(8, 7), constrained_layout=True)
    for i in range(rotors):
        axes[0].plot(log["t"], log[f"thrust_{i}"], label=f"rotor {i}")
        axes[1].plot(log["t"], log[f"mi_{i}"], label=f"$M_{i}$")
        axes[2].plot(log["t"], log[f"pi_{i}"], label=f"$P_{i}$")
    axes[0].set_ylabel("thrust [N]")
    axes[1].set_ylabel("motor index")
    axes[2].set_ylabel("propeller index")
    axes[2].set_xlabel("time [s]")
    for fault in summary.get("faults", []):
        for ax in axes:
            ax.axvline(fault["onset_s"], color="k", linestyle="--", linewidth=0.8)
    fdd = summary.get("fdd") or {}
    diagnosis = fdd if fdd.get("detected") else None
    if diagnosis:
        for ax in axes:
            ax.axvline(diagnosis["detection_s"], color="tab:red", linewidth=0.8)
    for ax in axes:
        ax.legend(loc="upper right", fontsize="small", ncol=rotors)
        ax.grid(alpha=0.3)
    outcome = "success" if result.success else "failed"
    found = f", rotor {diagnosis['rotor']} {diagnosis['kind']} isolated at {diagnosis['detection_s']:.3f} s" \
        if diagnosis else ", nothing isolated"
    axes[0].set_title(f"{summary['scenario']}, seed {summary['seed']}: {outcome}{found}")
    os.makedirs(os.path.dirname(os.path.abspath(args.png)), exist_ok=True)
    figure.savefig(args.png, dpi=110)
    print(f"{summary['scenario']}: {outcome}{found}; wrote {args.png}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
