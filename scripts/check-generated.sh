#!/usr/bin/env bash
# Fails when a generated file differs from what its generator makes now, as `gen-header --check` does
# for the header: the test stages' list (docs/dev/test-stages.txt from scripts/test.sh --list), the C test vectors (c-tests/like_vectors.inc from src/pattern/like-vectors.tsv), the
# table of accepted struct_size values in docs/api-conventions.md (from the code, x86_64 column; the
# i686 column is checked by the same test in the rust-x86 stage), the docs' snippets taken from compiled
# examples (tools/check-doc-snippets.py) and the
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
# The struct_size table: the Rust test that generates it fails when it differs from the code.
if out=$(cargo test -q --lib struct_size_table 2>&1); then
    echo "docs/api-conventions.md's struct_size table is up to date (x86_64)"
else
    grep -E "panicked|struct_size table|^  left|^ right" <<<"$out" | head -20 >&2 || true
    echo "docs/api-conventions.md's struct_size table differs from the code: run scripts/gen-struct-size-table.sh and commit it" >&2
    status=1
fi
# The docs' snippets marked as taken from a file ctest builds are still in that file.
python3 tools/check-doc-snippets.py || status=1
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
