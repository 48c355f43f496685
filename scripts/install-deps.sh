#!/usr/bin/env bash
# Installs every Debian package rotorguard builds, tests and runs with; with --fuzz also clang and
# its libFuzzer runtime, which only `make fuzz` uses; with --peers also git and TBB, which the peers
# `make peers` builds outside the sources need (docs/performance.md).
# Idempotent: does nothing (and needs no network or root) when all are present.
# Works as root or through sudo.
set -euo pipefail

packages=(
  build-essential cmake pkg-config
  libeigen3-dev        # linear algebra (core, vehicle, control)
  libyaml-cpp-dev      # scenario and vehicle files (io)
  libcli11-dev         # command-line parsing (apps/rotorguard)
  nlohmann-json3-dev   # summary.json, bench output (io, bench)
  libfmt-dev           # formatting in messages and logs
  libgtest-dev libgmock-dev  # tests
  libbenchmark-dev     # micro-benchmarks
  libceres-dev         # L-BFGS for trajectory optimisation (planning)
  coinor-libipopt-dev  # Ipopt: the NMPC's correctness oracle in tests (not linked by the product)
  liboctomap-dev       # OctoMap: the reference map `bench perception` measures the occupancy map against
  chromium             # headless browser of the report's browser test (viewer/test)
  slurm-wlm munge      # campaigns as Slurm job arrays; a single-node cluster in tests (scripts/local-slurm.sh)
  parallel             # GNU parallel: campaign shards across machines over ssh
  python3              # scripts/: the layering check (a test) and the behaviour snapshot
  python3-dev pybind11-dev  # the Python package (python/, docs/python.md)
  python3-numpy        # its arrays
  python3-matplotlib   # the Python examples' plots (examples/python/)
  python3-pytest       # its tests
  # ROS 1 (docs/ros.md): roscpp, the message generators, roscore, rostopic and rosbag's tools
  # (ros-core-dev), rosbag's C++ library, and tf2's messages; the build turns ROS on when they are here.
  ros-core-dev librosbag-dev libtf2-msgs-dev
  # the Python message classes `rostopic echo` needs for the node's outputs (odometry and path,
  # RViz markers; the tests echo them): ros-core-dev brings the C++ ones only
  python3-nav-msgs python3-visualization-msgs python3-sensor-msgs
)
if [ "${1:-}" = "--fuzz" ]; then
  packages+=(clang libclang-rt-14-dev)  # libFuzzer, with AddressSanitizer (docs/reliability.md)
elif [ "${1:-}" = "--peers" ]; then
  packages+=(git libtbb-dev)  # cloning the peers; KISS-ICP's parallel loops
elif [ $# -gt 0 ]; then
  echo "install-deps: unknown argument '$1'; expected none, --fuzz or --peers" >&2
  exit 2
fi
# Node.js and npm build the report viewer (viewer/); a machine that has them already keeps its own.
if ! command -v npm >/dev/null 2>&1 || ! command -v node >/dev/null 2>&1; then
  packages+=(nodejs npm)
fi

missing=()
for p in "${packages[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done

if [ ${#missing[@]} -eq 0 ]; then
  exit 0
fi

echo "install-deps: installing ${missing[*]}"
if [ "$(id -u)" -eq 0 ]; then
  sudo=()
elif command -v sudo >/dev/null 2>&1; then
  sudo=(sudo)
else
  echo "install-deps: missing packages (${missing[*]}) and neither root nor sudo is available" >&2
  exit 1
fi
export DEBIAN_FRONTEND=noninteractive
"${sudo[@]}" apt-get update -qq
"${sudo[@]}" apt-get install -y -qq --no-install-recommends "${missing[@]}"
