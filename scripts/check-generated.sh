#!/usr/bin/env bash
# Fails when a generated file differs from what its generator makes now, as `gen-header --check` does
# for the header: the test stages' list (docs/dev/test-stages.txt from scripts/test.sh --list), the C test vectors (c-tests/like_vectors.inc from src/pattern/like-vectors.tsv) and the
# case-folding table (src/pattern/fold_table.rs from the Unicode Character Database's CaseFolding.txt,
# which Debian's unicode-data package installs; Debian 12 ships Unicode 15.0.0, the table's version), and
# the hand-written mentions of the version in the README and docs/ against Cargo.toml (tools/check-versions.py).
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
cd "$root"
status=0
check() { # FILE COMMAND...
    local file=$1
    shift
    if "$@" | diff -u "$file" - >/dev/null; then
        echo "$file is up to date"
    else
        "$@" | diff -u "$file" - | head -20 >&2 || true
        echo "$file differs from what '$*' generates: regenerate and commit it" >&2
        status=1
    fi
}
check c-tests/like_vectors.inc python3 tools/gen-like-vectors.py
# The test stages as the docs list them: what `scripts/test.sh --list` prints.
check docs/dev/test-stages.txt scripts/test.sh --list
# The version as the README and the docs write it (find_package requests, file names, sample output).
python3 tools/check-versions.py || status=1
folding=${OPCCOMN_CASE_FOLDING:-/usr/share/unicode/CaseFolding.txt}
table_version=$(sed -n 's/^pub(crate) const UNICODE_VERSION: &str = "\(.*\)";/\1/p' src/pattern/fold_table.rs)
data_version=$(sed -n '1s/^# CaseFolding-\(.*\)\.txt.*/\1/p' "$folding")
if [ "$table_version" != "$data_version" ]; then
    echo "src/pattern/fold_table.rs is Unicode $table_version but $folding is Unicode ${data_version:-?}:" \
        "set OPCCOMN_CASE_FOLDING to CaseFolding.txt of Unicode $table_version, or regenerate the table" >&2
    exit 1
fi
check src/pattern/fold_table.rs python3 tools/gen-case-folding.py "$folding"
exit $status
