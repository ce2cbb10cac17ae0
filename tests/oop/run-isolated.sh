#!/bin/sh
# Runs one cross-process test program (under the emulator given first, when cross-compiling) with its
# output in a file, printed when it exits. The processes COM starts for it (the test server, the
# browser service) are Wine processes that inherit its Unix standard error; one that outlives the test
# would otherwise keep ctest reading that pipe, and the test would time out after it has passed.
log=$(mktemp) || exit 1
"$@" >"$log" 2>&1
rc=$?
cat "$log"
rm -f "$log"
exit "$rc"
