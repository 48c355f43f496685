"""The stack's nominal controller written again in Python (numpy), flown in place of the C++ one.

The cascade of src/control/nominal_controller.cc and position_loop.cc, line for line: position
PID with acceleration feed-forward -> thrust vector (eq. 1 solved for T z_B, rotor drag
compensated, tilt limited) -> attitude from the thrust direction and the reference yaw, body-rate
feed-forward from the reference jerk (Mellinger & Kumar 2011) and angular-acceleration feed-forward
from its snap (Faessler et al. 2018) -> rate loop -> wrench -> thrusts by
the effectiveness matrix's pseudo-inverse, clipped to [0, T_bar].

    PYTHONPATH=build/python /usr/bin/python3 examples/python/nominal_controller.py

flies configs/scenarios/lemniscate_2ms.yaml with it and with the C++ controller, and prints how
far apart the two flights were.
"""
import argparse
import math
import os
import sys

import numpy as np

import rotorguard

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))


def rotation(q):
    """The rotation matrix of a unit quaternion (w, x, y, z)."""
    w, x, y, z = q / norm(q)
    return np.array([
        [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
        [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
        [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
    ])


def quaternion(R):
    """The unit quaternion (w, x, y, z) of a rotation matrix (Shepperd's method, as Eigen's)."""
    t = R[0, 0] + R[1, 1] + R[2, 2]
    if t > 0:
        s = math.sqrt(t + 1.0)
        w = 0.5 * s
        s = 0.5 / s
        return np.array([w, (R[2, 1] - R[1, 2]) * s, (R[0, 2] - R[2, 0]) * s, (R[1, 0] - R[0, 1]) * s])
    i = int(np.argmax(np.diag(R)))
    j, k = (i + 1) % 3, (i + 2) % 3
    s = math.sqrt(R[i, i] - R[j, j] - R[k, k] + 1.0)
    q = np.zeros(4)
    q[1 + i] = 0.5 * s
    s = 0.5 / s
    q[0] = (R[k, j] - R[j, k]) * s
    q[1 + j] = (R[j, i] + R[i, j]) * s
    q[1 + k] = (R[k, i] + R[i, k]) * s
    return q


def cross(a, b):
    """a x b of two 3-vectors (numpy's cross is general and slow for one pair)."""
    return np.array([a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]])


def norm(v):
    return math.sqrt(v @ v)


def clip(v, low, high):
    """np.clip for a small array: the same values, without np.clip's per-call overhead (~5x)."""
    return np.minimum(np.maximum(v, low), high)


def quaternion_product(a, b):
    aw, av = a[0], a[1:]
    bw, bv = b[0], b[1:]
    return np.concatenate(([aw * bw - av @ bv], aw * bv + bw * av + cross(av, bv)))


class NominalController:
    """Thrusts [N] for the stack's estimate and reference, as the C++ NominalController computes."""

    def __init__(self, model, gains):
        self.m = model["mass_kg"]
        self.I = model["inertia_kg_m2"]
        self.drag = model["rotor_drag_kg_s"]
        self.yaw_damping = model["yaw_damping_n_m_s"]
        self.g = model["gravity_m_s2"]
        self.max_thrust = model["max_thrust_n"]
        self.hover = model["hover_thrusts_n"]
        B = model["effectiveness"]
        self.allocation = B.T @ np.linalg.inv(B @ B.T)  # the pseudo-inverse, as vehicle::PseudoInverse
        # stack.nominal's keys (scenario.options["stack"]["nominal"]), vectors as arrays.
        self.k = {key: np.asarray(value) if isinstance(value, list) else value for key, value in gains.items()}
        self.integral = np.zeros(3)
        self.last_t = None

    def __call__(self, t, estimate, reference):
        dt = 0.0 if self.last_t is None else t - self.last_t
        self.last_t = t
        if not estimate["valid"]:
            return self.hover.copy()
        wrench = self.wrench(estimate, reference, dt)
        thrust = clip(self.allocation @ wrench, 0.0, self.max_thrust)
        return thrust if math.isfinite(thrust.sum()) else self.hover.copy()

    def thrust_vector(self, est, ref, dt, R):
        """PositionLoop::DesiredThrustVector, with R the estimate's rotation matrix."""
        k = self.k
        e_p = ref["position"] - est["position"]
        if dt > 0.0:
            limit = k["integral_limit_m_s2"]
            self.integral = clip(self.integral + k["ki_position"] * e_p * dt, -limit, limit)
        a_cmd = ref["acceleration"] + k["kp_position"] * e_p + k["kd_velocity"] * (ref["velocity"] - est["velocity"]) \
            + self.integral
        f = self.m * (a_cmd + np.array([0.0, 0.0, self.g])) + R @ (self.drag * (R.T @ est["velocity"]))
        f[2] = max(f[2], 0.1 * self.m * self.g)
        max_horizontal = f[2] * math.tan(k["max_tilt_rad"])
        horizontal = norm(f[:2])
        if horizontal > max_horizontal:
            f[:2] *= max_horizontal / horizontal
        return f

    def wrench(self, est, ref, dt):
        """CascadedWrenchLaw::Compute: [T, tau_x, tau_y, tau_z]."""
        k = self.k
        R = rotation(est["attitude"])
        f_des = self.thrust_vector(est, ref, dt, R)
        z_des = f_des / norm(f_des)
        x_c = np.array([math.cos(ref["yaw"]), math.sin(ref["yaw"]), 0.0])
        y_des = cross(z_des, x_c)
        if norm(y_des) < 1e-6:
            y_des = R[:, 1]
        y_des = y_des / norm(y_des)
        x_des = cross(y_des, z_des)
        R_des = np.array((x_des, y_des, z_des)).T
        thrust = max(0.0, f_des @ R[:, 2])
        c = max(norm(f_des) / self.m, 0.1 * self.g)
        h = (ref["jerk"] - (z_des @ ref["jerk"]) * z_des) / c
        w_ff_des = np.array([-(h @ y_des), h @ x_des, ref["yaw_rate"] * z_des[2]])
        q = est["attitude"] / norm(est["attitude"])
        q_e = quaternion_product(q * np.array([1.0, -1.0, -1.0, -1.0]), quaternion(R_des))
        if q_e[0] < 0.0:
            q_e = -q_e
        w_des = 2.0 * k["k_attitude"] * q_e[1:] + R.T @ R_des @ w_ff_des
        rate_norm = norm(w_des)
        if rate_norm > k["max_rate_rad_s"]:
            w_des *= k["max_rate_rad_s"] / rate_norm
        w = est["angular_velocity"]
        alpha_des = k["k_rate"] * (w_des - w)
        tau = self.I @ alpha_des + cross(w, self.I @ w) + np.array([0.0, 0.0, self.yaw_damping * w[2]])
        if k["snap_feedforward"]:  # the tilt's angular acceleration from the snap (off by default)
            c_dot = z_des @ ref["jerk"]
            s = ref["snap"]
            alpha_ff_des = np.array([(-(y_des @ s) - 2.0 * c_dot * w_ff_des[0] + c * w_ff_des[1] * w_ff_des[2]) / c,
                                     ((x_des @ s) - 2.0 * c_dot * w_ff_des[1] - c * w_ff_des[0] * w_ff_des[2]) / c,
                                     0.0])
            tau = tau + self.I @ (R.T @ R_des @ alpha_ff_des)
        return np.concatenate(([thrust], tau))


def fly_with_python_controller(scenario, **kwargs):
    """Flies `scenario` with NominalController in place of the stack's; returns its RunResult."""
    flight = rotorguard.Flight(scenario, **kwargs)
    controller = NominalController(flight.stack.model, flight.scenario.options["stack"]["nominal"])
    while not flight.done:
        thrust = controller(flight.time_s, flight.stack.estimate, flight.stack.reference)
        # The stack's rule around its controller: motors off until the estimate is valid, once
        # landed, and when the remaining rotors cannot hover.
        if not flight.stack.estimate["valid"] or flight.stack.mode in ("landed", "flight_termination"):
            thrust = np.zeros_like(thrust)
        flight.step_control(thrust)
    return flight.finish()


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scenario", default=os.path.join(ROOT, "configs/scenarios/lemniscate_2ms.yaml"))
    parser.add_argument("--seed", type=int, default=1)
    args = parser.parse_args()
    python = fly_with_python_controller(args.scenario, seed=args.seed)
    native = rotorguard.run(args.scenario, seed=args.seed)
    gap = np.sqrt(sum((python.log[a] - native.log[a]) ** 2 for a in ("p_x", "p_y", "p_z")))
    print(f"{python.summary['scenario']}, seed {args.seed}: tracking RMSE {python.summary['tracking_rmse_m']:.4f} m "
          f"(Python controller) against {native.summary['tracking_rmse_m']:.4f} m (C++); "
          f"the two flights at most {gap.max() * 1e3:.3g} mm apart")
    return 0


if __name__ == "__main__":
    sys.exit(main())
