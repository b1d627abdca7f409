#!/bin/sh
# usage: tsan_canary_repeat.sh CANARY MODE
# Runs the ThreadSanitizer canary (tests/tsan_canary.cpp) in a racy mode up to 8 times, until TSan reports the
# race on g_shared, and prints that run's output (ctest's PASS_REGULAR_EXPRESSION reads it). On the CI's 2-core
# machine a single run of the bodies mode went unreported about one time in ten (2026-12-07): the race is
# there every time, TSan's report is not. A stage whose annotations or suppressions swallowed our races would
# stay silent in all 8 runs and fail.
out=""
for attempt in 1 2 3 4 5 6 7 8; do
  out=$("$1" "$2" 2>&1)
  case "$out" in
    *"ThreadSanitizer: data race"*g_shared*)
      printf '%s\n' "$out"
      exit 0
      ;;
  esac
done
printf '%s\n' "$out"
echo "tsan_canary_repeat: no report of the race on g_shared in 8 runs of mode $2" >&2
exit 1
