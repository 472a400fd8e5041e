#!/usr/bin/env bash
# The README's two commands, on a fresh Debian 12 machine (root, or sudo):
#   ./quickstart.sh run    install packages, build, run the main job -> out/
#   ./quickstart.sh test   install packages, build, run the whole suite with
#                          ctest, then again built with ASan + UBSan
set -euo pipefail
cd "$(dirname "$0")"
export DEBIAN_FRONTEND=noninteractive

# Debian 12 packages only; README "Dependencies" says what each is for.
PACKAGES=(build-essential cmake pkg-config libmujoco-dev libosmesa6-dev libeigen3-dev
          libopencv-dev catch2 libcli11-dev nlohmann-json3-dev libyaml-cpp-dev gnuplot-nox libserial-dev
          clang-14 libclang-rt-14-dev clang-format slurm-wlm munge)
JOBS=$(nproc)

install_packages() {
  local missing=()
  for p in "${PACKAGES[@]}"; do
    dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
  done
  if [ ${#missing[@]} -gt 0 ]; then
    local sudo=""
    [ "$(id -u)" -eq 0 ] || sudo="sudo"
    echo "quickstart: installing ${missing[*]}"
    $sudo apt-get update -qq
    $sudo apt-get install -y -qq --no-install-recommends "${missing[@]}"
  fi
}

build() {  # build DIR [cmake options...]
  local dir=$1; shift
  cmake -S . -B "$dir" -DFOVEA_WERROR=ON "$@" >/dev/null
  cmake --build "$dir" -j "$JOBS"
}

case "${1:-}" in
  run)
    install_packages
    build build -DCMAKE_BUILD_TYPE=Release
    mkdir -p out
    # The main job: a full FOVEA run (IDR, then 25 fixations) on the default
    # scene, cylinder_planes, scored against ground truth after each fixation.
    # --force: replace the run an earlier quickstart wrote there (only that).
    ./build/experiments/fovea run --scene cylinder_planes --out out/run --force
    echo "quickstart: pictures and figures are in out/run/ (summary.json, fixations.jsonl, map.ply, map_after_*.png, fixation_path.png)"
    ;;
  test)
    install_packages
    build build -DCMAKE_BUILD_TYPE=Release
    ctest --test-dir build -j "$JOBS" --output-on-failure
    # Memory errors and undefined behaviour fail the suite too. Built with
    # clang, whose libFuzzer drives the fuzz targets (label "fuzz", 30 s each)
    # in the same build; -O1, no debug info: the usual sanitizer setting.
    # The Slurm test (label "slurm") ran in the release pass: it tests the
    # cluster path, not memory. So did the "outcome" tests, which check what
    # whole runs achieve; their code runs here in the other end-to-end tests.
    build build-asan -DCMAKE_CXX_COMPILER=clang++-14 -DCMAKE_BUILD_TYPE=None -DCMAKE_CXX_FLAGS=-O1 -DFOVEA_SANITIZE=ON -DFOVEA_FUZZ=ON
    ASAN_OPTIONS=detect_leaks=1:abort_on_error=1 \
      LSAN_OPTIONS=suppressions=$PWD/tests/lsan.supp:print_suppressions=0 \
      UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 \
      ctest --test-dir build-asan -j "$JOBS" --output-on-failure -LE 'slurm|outcome'
    ;;
  *)
    echo "usage: $0 run|test" >&2
    exit 2
    ;;
esac
