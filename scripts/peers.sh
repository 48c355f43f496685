#!/usr/bin/env bash
# Builds the peers rotorguard is measured against side by side (docs/performance.md), outside the
# repository's sources: their code is never part of rotorguard, only driven by the programs of
# benchmarks/peers/ in one process beside rotorguard's own solver.
#
#   scripts/peers.sh [DIR]        (default: out/peers; `make peers` runs it)
#
# Clones each peer at the commit the published figures used into DIR/src, builds BLASFEO and HPIPM
# (static, the flags below), Sophus and robin-map into DIR/install and KISS-ICP in DIR/build, and
# leaves GCOPTER's header-only L-BFGS where it is.
# PEERS_GIT_BASE replaces https://github.com (a mirror, or a folder of clones named owner+name).
# Needs git and Debian's TBB (scripts/install-deps.sh --peers).
# Then: cmake -S . -B build -DROTORGUARD_PEERS_DIR=DIR && cmake --build build --target peer_qp peer_lbfgs peer_lio
set -euo pipefail

dir=$(realpath -m "${1:-out/peers}")
base=${PEERS_GIT_BASE:-https://github.com}
jobs=$(nproc 2>/dev/null || echo 2)

# owner/name, the commit the figures of docs/performance.md were measured with, and the one folder
# checked out where the rest is not needed (GCOPTER: its headers, not its demos' media).
peers=(
  "giaf/blasfeo 0ab5db3259c009ea62318a5e35622fe6de7ae554"
  "giaf/hpipm 87ef7a6ab773427a8c416030a2b9d075a744c223"
  "ZJU-FAST-Lab/GCOPTER e0444f6d47b84f972ced91746b05feb36ce1fd4f gcopter/include"
  "PRBonn/kiss-icp 4bd9a1054931bd037ef5e690122832faab621113 cpp"
  "strasdat/Sophus d0b7315a0d90fc6143defa54596a3a95d9fa10ec"
  "Tessil/robin-map 4ec1bf19c6a96125ea22062f38c2cf5b958e448e"
)

# BLASFEO's kernels for AVX2 and FMA (x86-64-v3, the flags rotorguard itself is built with) where the
# CPU has them; HPIPM's AVX target then. Elsewhere both build their generic C.
# KISS-ICP gets rotorguard's ISA flag too: the same Eigen code (Sophus' poses) on both sides of its
# interface must agree on vector width and alignment.
if grep -q ' avx2 ' /proc/cpuinfo 2>/dev/null && grep -q ' fma ' /proc/cpuinfo 2>/dev/null; then
  blasfeo_target=X64_INTEL_HASWELL
  hpipm_target=AVX
  isa_flags=-march=x86-64-v3
else
  blasfeo_target=GENERIC
  hpipm_target=GENERIC
  isa_flags=
fi

mkdir -p "$dir/src" "$dir/install"
for p in "${peers[@]}"; do
  read -r repo commit only <<< "$p"
  name=${repo#*/}
  src="$dir/src/$name"
  if [ -d "$base" ]; then url="$base/${repo/\//+}"; [ -d "$url/repo" ] && url="$url/repo"; else url="$base/$repo"; fi
  if [ ! -d "$src/.git" ]; then
    echo "peers: cloning $repo into $src"
    git clone -q --no-checkout "$url" "$src"
  fi
  [ -z "$only" ] || git -C "$src" sparse-checkout set --no-cone "/$only/"
  git -C "$src" -c advice.detachedHead=false checkout -q "$commit" \
    || { echo "peers: $repo has no commit $commit (fetch it: git -C $src fetch)" >&2; exit 1; }
done

build() {  # name, then cmake options
  local name=$1
  shift
  echo "peers: building $name ($*)"
  cmake -S "$dir/src/$name" -B "$dir/build/$name" -DCMAKE_BUILD_TYPE=Release \
    -DCMAKE_INSTALL_PREFIX="$dir/install" -DCMAKE_POSITION_INDEPENDENT_CODE=ON "$@" \
    > "$dir/build/$name.configure.log" 2>&1 || { cat "$dir/build/$name.configure.log"; exit 1; }
  cmake --build "$dir/build/$name" -j "$jobs" > "$dir/build/$name.build.log" 2>&1 \
    || { tail -40 "$dir/build/$name.build.log"; exit 1; }
  cmake --install "$dir/build/$name" > /dev/null
}
mkdir -p "$dir/build"
build blasfeo -DTARGET=$blasfeo_target -DLA=HIGH_PERFORMANCE -DBLASFEO_EXAMPLES=OFF -DBUILD_SHARED_LIBS=OFF
build hpipm -DTARGET=$hpipm_target -DBLASFEO_PATH="$dir/install" -DHPIPM_TESTING=OFF -DBUILD_SHARED_LIBS=OFF
# KISS-ICP (its C++ core and pipeline) on Sophus 1.24.6 and robin-map 1.4.0, the versions its own build
# fetches, and Debian's TBB (libtbb-dev: scripts/install-deps.sh --peers).
build Sophus -DBUILD_SOPHUS_TESTS=OFF -DBUILD_SOPHUS_EXAMPLES=OFF
build robin-map
echo "peers: building kiss-icp"
cmake -S "$dir/src/kiss-icp/cpp/kiss_icp" -B "$dir/build/kiss-icp" -DCMAKE_BUILD_TYPE=Release \
  -DCMAKE_CXX_FLAGS="$isa_flags" \
  -DCMAKE_PREFIX_PATH="$dir/install" -DUSE_CCACHE=OFF -DUSE_SYSTEM_SOPHUS=ON -DUSE_SYSTEM_TSL-ROBIN-MAP=ON \
  -DUSE_SYSTEM_TBB=ON -DUSE_SYSTEM_EIGEN3=ON > "$dir/build/kiss-icp.configure.log" 2>&1 \
  || { cat "$dir/build/kiss-icp.configure.log"; exit 1; }
cmake --build "$dir/build/kiss-icp" -j "$jobs" > "$dir/build/kiss-icp.build.log" 2>&1 \
  || { tail -40 "$dir/build/kiss-icp.build.log"; exit 1; }

# What the drivers report beside their figures.
{
  echo "{"
  echo "  \"blasfeo_target\": \"$blasfeo_target\", \"hpipm_target\": \"$hpipm_target\", \"kiss_icp_flags\": \"$isa_flags\","
  first=1
  for p in "${peers[@]}"; do
    [ $first = 1 ] || echo ","
    first=0
    read -r repo commit only <<< "$p"
    printf '  "%s": "%s"' "$repo" "$commit"
  done
  echo
  echo "}"
} > "$dir/peers.json"
echo "peers: built into $dir (BLASFEO $blasfeo_target, HPIPM $hpipm_target); now"
echo "  cmake -S . -B build -DROTORGUARD_PEERS_DIR=$dir && cmake --build build --target peer_qp peer_lbfgs peer_lio"
