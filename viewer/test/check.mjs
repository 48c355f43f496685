// The viewer tests' one assertion: prints ok/FAIL per check and sets the exit code at the end.
const failures = [];

export function check(ok, message) {
  console.log(`${ok ? "ok  " : "FAIL"} ${message}`);
  if (!ok) failures.push(message);
}

/** Exits 1 when a check failed. */
export function finish() {
  if (failures.length > 0) {
    console.error(`${failures.length} check(s) failed`);
    process.exit(1);
  }
}
