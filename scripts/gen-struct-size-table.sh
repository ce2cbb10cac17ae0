#!/usr/bin/env bash
# Writes the table of accepted `struct_size` values in docs/api-conventions.md from the code (each
# structure's `SizedStruct::SIZES`; src/struct_size_table.rs): the x86_64 column from the Rust test run
# on this machine, the i686 column from the same test built for i686-pc-windows-gnu and run under
# 32-bit Wine (in the Wine prefix of build/windows, made as scripts/test.sh makes it).
#
# The drift check is the test itself: `cargo test --lib struct_size` fails when the column of the
# target it runs on differs from the code, or a cell is missing (scripts/check-generated.sh runs it for
# x86_64 in the lint stage; the rust-x86 stage runs it for i686).
# Usage: scripts/gen-struct-size-table.sh
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
cd "$root"
OPCCOMN_BLESS=1 cargo test -q --lib struct_size_table -- --test-threads=1 >/dev/null
echo "docs/api-conventions.md: x86_64 column written"
command -v wine >/dev/null || { echo "gen-struct-size-table.sh: the i686 column needs Wine (32-bit)" >&2; exit 1; }
. scripts/wine-env.sh "$root/build/windows"
# RUST_BACKTRACE=0 as in the rust-x86 stage (Debian 12's 32-bit Wine and panics with backtraces).
OPCCOMN_BLESS=1 RUST_BACKTRACE=0 CARGO_TARGET_I686_PC_WINDOWS_GNU_RUNNER=wine \
    cargo test -q --target i686-pc-windows-gnu --lib struct_size_table >/dev/null
echo "docs/api-conventions.md: i686 column written"
# Both columns as written, checked once more on this machine.
cargo test -q --lib struct_size_table >/dev/null
