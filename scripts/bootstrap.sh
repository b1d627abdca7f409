#!/usr/bin/env bash
# Single entry point of FluidPlaying on Debian 12: installs the packages, builds, and runs the demo or the tests.
#   bash scripts/bootstrap.sh demo    install, build, open the desktop app (or, with no display, render the hand
#                                     tank with a recorded hand into out/demo_frames/ as PNG)
#   bash scripts/bootstrap.sh test    install, check formatting, build, run all tests, then the sanitizer tests
#                                     (ASan+UBSan), the ThreadSanitizer tests (docs/robustness.md, "Races";
#                                     FP_CI_TSAN=0 skips them) and the fuzzers (30 s each, FUZZ_SECONDS; fewer
#                                     than FUZZ_MIN_RUNS=1000 inputs a 30 s fails)
#   bash scripts/bootstrap.sh build   install and build only
# Environment: FP_JOBS (default 2) sets the build and ctest parallelism; FP_CI_TSAN=0 skips the ThreadSanitizer
# stage, FP_TSAN_SECONDS (default 1200) caps its tests.
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

# Stage timing for the summary: `timed NAME COMMAND...` runs the command and records its wall time.
stage_times=()
timed() {
  local name="$1" start status=0
  shift
  start=$(date +%s)
  "$@" || status=$?
  stage_times+=("${name} $(($(date +%s) - start)) s")
  return "${status}"
}

run_sanitizer_tests() {
  section "Sanitizer build (ASan+UBSan, build-asan/)"
  # Called as `run_sanitizer_tests || ...`, where set -e is off: each step checks its own status; a build that
  # fails stops the whole run.
  cmake -S . -B build-asan -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo -DFP_SANITIZE=ON -DFP_WERROR=ON ||
    die "the sanitizer build could not be configured"
  cmake --build build-asan -j"${JOBS}" || die "the sanitizer build failed"
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

# ThreadSanitizer (docs/robustness.md, "Races") over the simulation's unit tests, the app loop's (AppSessionTest,
# AppLoopTest: the steps run on a TBB task or a thread beside the frame), the small physics tests and the canary
# that proves a race is still reported (TsanCanary.*, tests/tsan_canary.cpp). TBB as Debian ships it: its
# libtbb is not instrumented, so sim/parallel.h states the spawn and join edges of every parallel call, and
# tests/tsan.supp suppresses only races inside TBB's own objects, each with its reason. Any report fails the
# test (halt_on_error). Only the four targets are built (559 CPU-s, about 5 min on CI's 2 cores); the tests
# are capped at FP_TSAN_SECONDS (default 1200) in all, a run past the cap fails the stage.
readonly TSAN_TARGETS=(test_sim_unit test_app_unit test_physics tsan_canary)
run_tsan_tests() {
  section "ThreadSanitizer build (build-tsan/)"
  cmake -S . -B build-tsan -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo -DFP_TSAN=ON -DFP_WERROR=ON ||
    die "the ThreadSanitizer build could not be configured"
  cmake --build build-tsan -j"${JOBS}" --target "${TSAN_TARGETS[@]}" || die "the ThreadSanitizer build failed"
  local status=0
  local -a tsan_env=(
    "TSAN_OPTIONS=suppressions=${PWD}/tests/tsan.supp:halt_on_error=1:second_deadlock_stack=1:history_size=7"
  )
  local cap="${FP_TSAN_SECONDS:-1200}" start
  start=$(date +%s)
  section "ThreadSanitizer tests: unit (simulation, app loop, canary)"
  # the suites built above (the others are not in build-tsan); the architecture rules run in the Release build
  env "${tsan_env[@]}" timeout "${cap}" ctest --test-dir build-tsan --output-on-failure -j"${JOBS}" -L unit \
    -E '^Architecture\.' --no-tests=error || status=1
  section "ThreadSanitizer tests: physics *Small*"
  local left=$((cap - ($(date +%s) - start)))
  ((left > 0)) || left=1
  env "${tsan_env[@]}" timeout "${left}" ctest --test-dir build-tsan --output-on-failure -j"${JOBS}" -L physics \
    -R Small --no-tests=error || status=1
  return "${status}"
}

# libFuzzer (clang 14, libfuzzer-14-dev): every file format read from outside, 30 s each over the seeds of
# tests/fuzz/ (see tests/fuzz/README.md). A crash leaves build-fuzz/crash-TARGET-* to reproduce.
readonly FUZZ_TARGETS=(scene preset pose_track joint_track state)
run_fuzzers() {
  [[ "${FUZZ_SECONDS:-30}" =~ ^[1-9][0-9]*$ ]] ||
    die "FUZZ_SECONDS must be a whole number of seconds above 0, not '${FUZZ_SECONDS}'"
  [[ "${FUZZ_MIN_RUNS:-1000}" =~ ^(0|[1-9][0-9]*)$ ]] ||
    die "FUZZ_MIN_RUNS must be a whole number, not '${FUZZ_MIN_RUNS}'"
  section "Fuzz build (libFuzzer, clang, build-fuzz/)"
  command -v clang++ >/dev/null 2>&1 || die "clang++ not found (package clang)"
  # no -Werror here: the Release build holds gcc's warnings at zero; clang's extra ones are only shown
  cmake -S . -B build-fuzz -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_C_COMPILER=clang \
    -DCMAKE_CXX_COMPILER=clang++ -DFP_FUZZ=ON -DFP_BUILD_TESTS=OFF ||
    die "the fuzz build could not be configured"
  local targets=() name
  for name in "${FUZZ_TARGETS[@]}"; do
    targets+=("fuzz_${name}")
  done
  cmake --build build-fuzz -j"${JOBS}" --target "${targets[@]}" || die "the fuzz build failed"
  local status=0
  # the state seed must match today's format and the target's scene, or the fuzzer only mutates a header
  FP_FUZZ_CHECK_SEED=tests/fuzz/state/seed.bin build-fuzz/tests/fuzz/fuzz_state || status=1
  for name in "${FUZZ_TARGETS[@]}"; do
    section "Fuzz: fuzz_${name} (${FUZZ_SECONDS:-30} s)"
    mkdir -p "build-fuzz/corpus/${name}"
    # new inputs go to build-fuzz/corpus/, the seeds are only read; -print_final_stats gives the exec count.
    # -timeout=60: every input runs in milliseconds; on a starved machine 10 s gave false "timeouts"
    local log="build-fuzz/fuzz_${name}.log"
    if ! build-fuzz/tests/fuzz/"fuzz_${name}" -max_total_time="${FUZZ_SECONDS:-30}" -timeout=60 \
      -rss_limit_mb=2048 -print_final_stats=1 -artifact_prefix="build-fuzz/crash-${name}-" \
      "build-fuzz/corpus/${name}" "tests/fuzz/${name}" >"${log}" 2>&1; then
      status=1
      tail -n 60 "${log}"
    fi
    grep -E "stat::number_of_executed_units|Done [0-9]+ runs" "${log}" || true
    # A fuzzer that spends its budget before its first inputs tests nothing and passes: fuzz_state once ran
    # 4 inputs in 30 s, its start-up under the coverage hooks (tests/fuzz/coverage_ignore.txt) taking 26 s.
    # Each target runs hundreds to thousands of inputs a second here, so fewer than FUZZ_MIN_RUNS in 30 s (in
    # proportion for another FUZZ_SECONDS) fails the stage.
    local runs least=$(( ${FUZZ_MIN_RUNS:-1000} * ${FUZZ_SECONDS:-30} / 30 ))
    runs="$(sed -n 's/^stat::number_of_executed_units: *\([0-9]*\).*/\1/p' "${log}" | tail -n 1)"
    if [[ -z "${runs}" || "${runs}" -lt "${least}" ]]; then
      echo "fuzz_${name} ran ${runs:-no} inputs in ${FUZZ_SECONDS:-30} s, under ${least} (FUZZ_MIN_RUNS a 30 s):" \
        "too few to test anything; a slow start-up is the usual cause (see ${log})"
      status=1
    fi
  done
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
  # With the ffmpeg program there, the frames also go into out/demo.mp4.
  local video=()
  if command -v ffmpeg > /dev/null; then
    video=(--video out/demo.mp4)
  fi
  ./build/fluidplaying --headless --render --scene assets/scenes/hand_tank.json --hand-script assets/hands/push.csv \
    --frames 120 --width 960 --height 540 --out out/demo_frames --stats out/demo_stats.json "${video[@]}"
  echo
  if [[ ${#video[@]} -gt 0 ]]; then
    echo "demo output: out/demo.mp4, PNG frames in out/demo_frames/, statistics in out/demo_stats.json"
  else
    echo "demo output: PNG frames in out/demo_frames/, statistics in out/demo_stats.json (no ffmpeg: no out/demo.mp4)"
  fi
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
    timed format check_format || failures+=("format")
    timed build build || die "the build failed"
    timed tests run_tests || failures+=("tests")
    timed asan run_sanitizer_tests || failures+=("sanitizer tests")
    # on by default; FP_CI_TSAN=0 skips it (docs/robustness.md, "Races")
    if [[ "${FP_CI_TSAN:-1}" != 0 ]]; then
      timed tsan run_tsan_tests || failures+=("thread sanitizer tests")
    fi
    timed fuzz run_fuzzers || failures+=("fuzzers")
    section "Summary"
    echo "stage times: ${stage_times[*]}"
    if [[ ${#failures[@]} -gt 0 ]]; then
      echo "FAILED: ${failures[*]}"
      exit 1
    fi
    echo "all checks passed"
    ;;
esac
