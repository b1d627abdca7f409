#!/usr/bin/env bash
# Single entry point of FluidPlaying on Debian 12: installs the packages, builds, and runs the demo or the tests.
#   bash scripts/bootstrap.sh demo    install, build, open the desktop app (or, with no display, render the hand
#                                     tank with a recorded hand into out/demo_frames/ as PNG)
#   bash scripts/bootstrap.sh test    install, check formatting, build, run all tests, then the sanitizer tests
#   bash scripts/bootstrap.sh build   install and build only
# Environment: FP_JOBS (default 2) sets the build and ctest parallelism.
set -euo pipefail

readonly PACKAGES=(
  build-essential cmake ninja-build pkg-config git
  libeigen3-dev libtbb-dev nlohmann-json3-dev
  libglfw3-dev libglew-dev libgl-dev libimgui-dev
  libopenxr-dev libopenxr-loader1 libosmesa6-dev libegl-dev
  libpng-dev libstb-dev
  googletest libgtest-dev libgmock-dev
  xvfb xauth clang-format
  libcli11-dev ffmpeg
  openxr-layer-corevalidation libopenxr-utils
  clang libfuzzer-14-dev libclang-rt-14-dev
)
readonly FORMAT_DIRS=(sim engine render input tests)

usage() {
  echo "usage: bash scripts/bootstrap.sh {demo|test|build}" >&2
  echo "  demo   install packages, build, open the desktop app (no display: render PNG frames into out/)" >&2
  echo "  test   install packages, check formatting, build, run the tests and the sanitizer tests" >&2
  echo "  build  install packages and build" >&2
}

section() { printf '\n=== %s ===\n' "$*"; }
die() {
  echo "bootstrap: error: $*" >&2
  exit 1
}

MODE="${1:-}"
case "${MODE}" in
  demo | test | build) ;;
  *)
    usage
    exit 2
    ;;
esac
if [[ $# -gt 1 ]]; then
  usage
  exit 2
fi

# Every path below is relative to the repository root, wherever the script is called from.
cd "$(dirname "${BASH_SOURCE[0]}")/.."

JOBS="${FP_JOBS:-2}"
[[ "${JOBS}" =~ ^[1-9][0-9]*$ ]] || die "FP_JOBS must be a positive integer, got '${JOBS}'"
export DEBIAN_FRONTEND=noninteractive

install_packages() {
  section "Packages"
  command -v dpkg-query >/dev/null 2>&1 || die "dpkg-query not found: this script targets Debian 12"
  local missing=() pkg
  for pkg in "${PACKAGES[@]}"; do
    # db:Status-Status is exactly "installed" only for a fully installed package (not half-configured/removed).
    if [[ "$(dpkg-query -W -f='${db:Status-Status}' "${pkg}" 2>/dev/null || true)" != "installed" ]]; then
      missing+=("${pkg}")
    fi
  done
  if [[ ${#missing[@]} -eq 0 ]]; then
    echo "all ${#PACKAGES[@]} packages already installed"
    return
  fi
  echo "missing: ${missing[*]}"
  local sudo=()
  if [[ "${EUID}" -ne 0 ]]; then
    command -v sudo >/dev/null 2>&1 ||
      die "not root and sudo not found; install as root: apt-get install -y --no-install-recommends ${missing[*]}"
    # sudo resets the environment, so the noninteractive frontend is passed explicitly.
    sudo=(sudo DEBIAN_FRONTEND=noninteractive)
  fi
  "${sudo[@]}" apt-get update
  "${sudo[@]}" apt-get install -y --no-install-recommends "${missing[@]}"
}

build() {
  section "Build (Release, build/)"
  cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=Release -DFP_WERROR=ON
  cmake --build build -j"${JOBS}"
}

# Prints the files that clang-format would change; returns non-zero when there are any.
check_format() {
  section "Format check (clang-format)"
  local dirs=() dir
  for dir in "${FORMAT_DIRS[@]}"; do
    if [[ -d "${dir}" ]]; then
      dirs+=("${dir}")
    fi
  done
  local files=() bad=() file
  if [[ ${#dirs[@]} -gt 0 ]]; then
    mapfile -t files < <(find "${dirs[@]}" -type f \( -name '*.cpp' -o -name '*.h' \) | sort)
  fi
  for file in "${files[@]}"; do
    if ! clang-format --dry-run -Werror "${file}" >/dev/null 2>&1; then
      bad+=("${file}")
    fi
  done
  if [[ ${#bad[@]} -gt 0 ]]; then
    echo "not clang-formatted (fix with: clang-format -i FILE):"
    printf '  %s\n' "${bad[@]}"
    return 1
  fi
  echo "${#files[@]} files formatted"
}

have_display() { [[ -n "${DISPLAY:-}" || -n "${WAYLAND_DISPLAY:-}" ]]; }

run_tests() {
  section "Tests (ctest, build/)"
  if have_display; then
    ctest --test-dir build --output-on-failure -j"${JOBS}"
  else
    # The window tests (label gl, tests/app) need an X server; Xvfb gives them one with llvmpipe's GLX.
    command -v xvfb-run >/dev/null 2>&1 || die "xvfb-run not found (package xvfb) and no DISPLAY for the window tests"
    xvfb-run -a -s "-screen 0 1280x1024x24" ctest --test-dir build --output-on-failure -j"${JOBS}"
  fi
}

run_sanitizer_tests() {
  section "Sanitizer build (ASan+UBSan, build-asan/)"
  # Called as `run_sanitizer_tests || ...`, where set -e is off: each step checks its own status.
  cmake -S . -B build-asan -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo -DFP_SANITIZE=ON -DFP_WERROR=ON || return 1
  cmake --build build-asan -j"${JOBS}" || return 1
  local status=0
  local -a sanitizer_env=(
    ASAN_OPTIONS=detect_leaks=1:abort_on_error=1
    UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1
  )
  section "Sanitizer tests: unit"
  # A label typo must not turn into a silently empty run.
  env "${sanitizer_env[@]}" ctest --test-dir build-asan --output-on-failure -j"${JOBS}" -L unit --no-tests=error ||
    status=1
  section "Sanitizer tests: physics *Small*"
  # The small physics cases are cheap enough under the sanitizers; there may be none yet, which is not a failure.
  env "${sanitizer_env[@]}" ctest --test-dir build-asan --output-on-failure -j"${JOBS}" -L physics -R Small \
    --no-tests=ignore || status=1
  return "${status}"
}

run_demo() {
  section "Demo"
  mkdir -p out
  if have_display; then
    # The desktop app on the tank with the hand; F1 in the window lists the controls.
    echo "opening the window (F1: controls; close it to end the demo)"
    if ./build/fluidplaying; then
      return
    fi
    echo "the window did not run; rendering the headless demo instead"
  fi
  # No display: the same scene and app loop headless, a recorded hand pushing the water, rendered through OSMesa.
  ./build/fluidplaying --headless --render --scene assets/scenes/hand_tank.json --hand-script assets/hands/push.csv \
    --frames 120 --width 960 --height 540 --out out/demo_frames --stats out/demo_stats.json
  echo
  echo "demo output: PNG frames in out/demo_frames/, statistics in out/demo_stats.json"
  echo "(make a video: ffmpeg -framerate 60 -i out/demo_frames/frame_%05d.png out/demo.mp4)"
}

install_packages

case "${MODE}" in
  build)
    build
    ;;
  demo)
    build
    run_demo
    ;;
  test)
    # Keep going after a format or test failure so one run reports all of them; a build failure stops at once.
    failures=()
    check_format || failures+=("format")
    build
    run_tests || failures+=("tests")
    run_sanitizer_tests || failures+=("sanitizer tests")
    section "Summary"
    if [[ ${#failures[@]} -gt 0 ]]; then
      echo "FAILED: ${failures[*]}"
      exit 1
    fi
    echo "all checks passed"
    ;;
esac
