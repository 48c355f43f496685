// Helpers over the flight's columns (the report's "series": log.csv thinned, one array per column).

/** Index of the last sample at or before t (0 before the first). */
export function indexAt(times, t) {
  let lo = 0;
  let hi = times.length - 1;
  if (hi < 0 || t <= times[0]) return 0;
  if (t >= times[hi]) return hi;
  while (hi - lo > 1) {
    const mid = (lo + hi) >> 1;
    if (times[mid] <= t) lo = mid;
    else hi = mid;
  }
  return lo;
}

/** Roll, pitch, yaw [rad] (ZYX) of a body-to-world quaternion. */
export function eulerFromQuaternion(w, x, y, z) {
  const roll = Math.atan2(2 * (w * x + y * z), 1 - 2 * (x * x + y * y));
  const pitch = Math.asin(Math.max(-1, Math.min(1, 2 * (w * y - z * x))));
  const yaw = Math.atan2(2 * (w * z + x * y), 1 - 2 * (y * y + z * z));
  return [roll, pitch, yaw];
}

/** Number of rotors: the cmd_i columns present. */
export function rotorCount(series) {
  let n = 0;
  while (series[`cmd_${n}`]) n += 1;
  return n;
}

/** Unwraps an angle sequence so that it has no 2π jumps (a spinning vehicle's yaw). */
export function unwrap(angles) {
  const out = new Array(angles.length);
  let offset = 0;
  for (let i = 0; i < angles.length; i += 1) {
    if (i > 0) {
      const d = angles[i] - angles[i - 1];
      if (d > Math.PI) offset -= 2 * Math.PI;
      else if (d < -Math.PI) offset += 2 * Math.PI;
    }
    out[i] = angles[i] + offset;
  }
  return out;
}

export function fmt(value, digits = 3) {
  if (value === null || value === undefined) return "–";
  if (typeof value === "number") return Number.isInteger(value) ? String(value) : value.toFixed(digits);
  return String(value);
}
