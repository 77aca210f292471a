#!/bin/sh
# Runs a test binary under umockdev's preload library, so its emulated device nodes work
# (docs/testing.md). The CROSSCOMPILING_EMULATOR of the *_emulated test targets.
# Sanitizer builds: ASan wants its runtime first in the library list, which LD_PRELOAD breaks;
# umockdev's preload only wraps libc calls (open, ioctl, ...), so that check is switched off.
ASAN_OPTIONS="${ASAN_OPTIONS:+$ASAN_OPTIONS:}verify_asan_link_order=0"
export ASAN_OPTIONS
exec umockdev-wrapper "$@"
